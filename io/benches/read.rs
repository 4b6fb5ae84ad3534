//! Parsing throughput of the text readers, in bytes per second of the source: the EuRoC file
//! shipped in `tests/data` (integer ns, 17-digit readings) repeated to 8× its length with
//! shifted timestamps, read from memory through `ImuReader` (lines, fields, numbers, order and
//! finiteness checks). Target: ≥ 150 MB/s.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use preint_io::{ImuReader, ReadOptions};
use std::hint::black_box;

/// The EuRoC rows `copies` times, each copy shifted past the previous one.
fn euroc_text(copies: i64) -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/euroc/V1_01_easy_imu0.csv"
    );
    let text = std::fs::read_to_string(path).expect("tests/data/euroc is in the repository");
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    let rows: Vec<(i64, &str)> = lines
        .map(|l| {
            let (t, rest) = l.split_once(',').unwrap();
            (t.parse().unwrap(), rest)
        })
        .collect();
    let span = rows[rows.len() - 1].0 - rows[0].0 + 5_000_000;
    for c in 0..copies {
        for (t, rest) in &rows {
            out.push_str(&format!("{},{rest}\n", t + c * span));
        }
    }
    out
}

fn read(c: &mut Criterion) {
    let text = euroc_text(8);
    let mut g = c.benchmark_group("read");
    g.throughput(Throughput::Bytes(text.len() as u64));
    g.sample_size(10);
    g.bench_function("euroc_csv", |b| {
        b.iter(|| {
            let r = ImuReader::from_text(black_box(&text), "bench.csv", &ReadOptions::euroc());
            let n = r.unwrap().map(|s| s.unwrap().t_ns).fold(0i64, |a, t| a ^ t);
            black_box(n)
        })
    });
    g.finish();
}

criterion_group!(benches, read);
criterion_main!(benches);
