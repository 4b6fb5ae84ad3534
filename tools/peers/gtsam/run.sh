#!/usr/bin/env bash
# GTSAM 4.3's C++ preintegration beside preint's, in the same run (docs/PERFORMANCE.md,
# "Against GTSAM 4.3, in the same run"). Run by hand, outside CI:
#
#   python3 -m venv target/python-venv && target/python-venv/bin/pip install gtsam==4.3.0
#   apt-get install g++ libeigen3-dev          # Debian: the compiler and Eigen 3.4 headers
#   tools/peers/gtsam/run.sh                   # ROUNDS=15 RUNS=11 SAMPLES=100000 by default
#
# Environment: VENV (a venv with the PyPI gtsam 4.3.0 wheel, default target/python-venv),
# EIGEN (Eigen's include directory, default /usr/include/eigen3), CXX (default g++), ROUNDS,
# RUNS, SAMPLES, OUT (build and result directory, default target/peers/gtsam), CARGO_TARGET_DIR.
#
# 1. Builds bench.cpp with $CXX -O3 -DNDEBUG against the wheel's libgtsam (the timed code is the
#    wheel's own compiled integrateMeasurement; bench.cpp declares the entry points it calls)
#    and `preint` (cargo build --release -p preint-cli).
# 2. Checks: the parameters as libgtsam prints them; GTSAM's ΔR, Δv, Δp and covariance after the
#    stream against the wheel's Python bindings (bit for bit) and against preint's `integrate`
#    on the same samples (GTSAM Manifold ≡ preint euler, GTSAM Galilean ≡ preint galilean).
#    With valgrind installed, instructions per integrateMeasurement call (callgrind), to set
#    beside tools/instructions.sh's counts for preint.
# 3. ROUNDS rounds, each the GTSAM harness (every backend, median of RUNS runs of SAMPLES
#    samples) and then `preint speed --samples SAMPLES` (median of 11 runs); prints min / median
#    / max over the rounds and the per-round ratios preint / GTSAM.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
VENV=${VENV:-$ROOT/target/python-venv}
EIGEN=${EIGEN:-/usr/include/eigen3}
CXX=${CXX:-g++}
ROUNDS=${ROUNDS:-15}
RUNS=${RUNS:-11}
SAMPLES=${SAMPLES:-100000}
OUT=${OUT:-$ROOT/target/peers/gtsam}
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
mkdir -p "$OUT"

SITE=$(ls -d "$VENV"/lib/python3*/site-packages | head -n 1)
VERSION=$(sed -n 's/^Version: //p' "$SITE"/gtsam-*.dist-info/METADATA 2>/dev/null | head -n 1)
if [ "$VERSION" != "4.3.0" ]; then
  echo "run.sh: needs the PyPI gtsam 4.3.0 wheel in $VENV (found '${VERSION:-none}'):" >&2
  echo "  $VENV/bin/pip install gtsam==4.3.0" >&2
  exit 1
fi
LIBS=$SITE/gtsam.libs
SO=$(ls "$LIBS"/libgtsam-*.so.4.3.0 | head -n 1)
[ -f "$EIGEN/Eigen/Core" ] || { echo "run.sh: no Eigen headers in $EIGEN (apt-get install libeigen3-dev)" >&2; exit 1; }

echo "== build"
FLAGS=(-std=c++17 -O3 -DNDEBUG -D_GLIBCXX_USE_CXX11_ABI=0)
"$CXX" "${FLAGS[@]}" -I"$EIGEN" "$ROOT/tools/peers/gtsam/bench.cpp" -o "$OUT/bench" "$SO" \
  -Wl,-rpath,"$LIBS"
echo "$("$CXX" --version | head -n 1) ${FLAGS[*]}; Eigen $(sed -n 's/#define EIGEN_\(WORLD\|MAJOR\|MINOR\)_VERSION //p' "$EIGEN/Eigen/src/Core/util/Macros.h" | paste -sd.)"
echo "libgtsam: $SO ($(strings "$SO" | grep -m 1 '^GCC: '))"
(cd "$ROOT" && CARGO_TARGET_DIR=$TARGET cargo build -q --release -p preint-cli)
PREINT=$TARGET/release/preint
echo "preint: $PREINT ($(rustc --version))"

echo "== parameters, as libgtsam prints them"
"$OUT/bench" --params | tr '\n' ' ' | sed 's/  */ /g; s/PreintegrationCombinedParams/\nPreintegrationCombinedParams/'
echo

echo "== deltas after $SAMPLES samples"
"$OUT/bench" --deltas --samples "$SAMPLES" > "$OUT/deltas-cpp.txt"
"$OUT/bench" --csv "$OUT/stream.csv" --samples "$SAMPLES"
"$VENV/bin/python" - "$SAMPLES" > "$OUT/deltas-py.txt" <<'EOF'
# The same stream and parameters through the wheel's Python bindings.
import sys
import numpy as np
import gtsam
n = int(sys.argv[1])
k = np.arange(n); t = k * 0.005
gyro = np.stack([0.3 * np.sin(1.1 * t), 0.2 * np.cos(0.7 * t), 0.5 * np.sin(0.3 * t) + 0.1], 1)
acc = np.stack([0.5 * np.sin(0.9 * t), 0.3 * np.cos(1.3 * t), 9.81 + 0.2 * np.sin(0.5 * t)], 1)
t_ns = k * 5_000_000
I = np.eye(3)
def fill(p):
    p.setGyroscopeCovariance(I * 1.6968e-4**2)
    p.setAccelerometerCovariance(I * 2.0e-3**2)
    p.setIntegrationCovariance(I * 0.0)
    return p
p = fill(gtsam.PreintegrationParams.MakeSharedU(9.81))
pc = fill(gtsam.PreintegrationCombinedParams.MakeSharedU(9.81))
pc.setBiasAccCovariance(I * 3.0e-3**2)
pc.setBiasOmegaCovariance(I * 1.9393e-5**2)
for name, make in [("manifold", lambda: gtsam.PreintegratedImuMeasurementsManifold(p)),
                   ("tangent", lambda: gtsam.PreintegratedImuMeasurements(p)),
                   ("liegroup", lambda: gtsam.PreintegratedImuMeasurementsLieGroup(p)),
                   ("galilean", lambda: gtsam.PreintegratedImuMeasurementsG(p)),
                   ("combined", lambda: gtsam.PreintegratedCombinedMeasurements(pc, gtsam.imuBias.ConstantBias()))]:
    m = make()
    for i in range(n - 1):
        m.integrateMeasurement(acc[i], gyro[i], (int(t_ns[i + 1]) - int(t_ns[i])) * 1e-9)
    vals = list(m.deltaRij().matrix().flatten(order="F")) + list(m.deltaVij()) + list(m.deltaPij())
    vals += list(m.preintMeasCov().flatten(order="F"))
    print(name, " ".join("%.17g" % x for x in vals))
EOF
if cmp -s "$OUT/deltas-cpp.txt" "$OUT/deltas-py.txt"; then
  echo "C++ harness = the wheel's Python bindings, bit for bit (ΔR, Δv, Δp, preintMeasCov; 5 backends)"
else
  echo "C++ harness and the wheel's Python bindings DIFFER:"; diff "$OUT/deltas-cpp.txt" "$OUT/deltas-py.txt" | cut -c1-200
  exit 1
fi
for s in euler midpoint galilean; do
  "$PREINT" integrate --imu "$OUT/stream.csv" --scheme "$s" --no-unit-check --json > "$OUT/preint-$s.json"
done
python3 - "$OUT" <<'EOF'
# GTSAM's covariance is in [rot, pos, vel] with pos and vel in its NavState chart: T = diag(I,
# ΔR, ΔR) maps it to preint's chart, then [φ, p, v] is reordered to preint's [δφ, δv, δp]
# (python/tests/test_gtsam_manifold.py).
import json, math, sys
out = sys.argv[1]
def mat(x, n):
    return [[x[c * n + r] for c in range(n)] for r in range(n)]  # column-major
def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(len(b))) for j in range(len(b[0]))] for i in range(len(a))]
def flat(a):
    return [v for row in a for v in (row if isinstance(row, list) else [row])]
def rel(a, b):
    fa, fb = flat(a), flat(b)
    return math.sqrt(sum((p - q) ** 2 for p, q in zip(fa, fb))) / math.sqrt(sum(q * q for q in fb))
gt = {}
for line in open(f"{out}/deltas-cpp.txt"):
    w = line.split(); x = [float(v) for v in w[1:]]
    gt[w[0]] = (mat(x[0:9], 3), x[9:12], x[12:15], x[15:])
print(f"{'GTSAM':<9} {'preint':<9} {'ΔR':>9} {'Δv':>9} {'Δp':>9} {'9x9 cov':>9}   (relative Frobenius difference after the stream)")
for g, s in [("manifold", "euler"), ("galilean", "galilean"), ("tangent", "midpoint")]:
    R, v, p, c = gt[g]
    d = json.load(open(f"{out}/preint-{s}.json"))
    T = [[0.0] * 9 for _ in range(9)]
    for i in range(3):
        T[i][i] = 1.0
        for j in range(3):
            T[3 + i][3 + j] = T[6 + i][6 + j] = R[i][j]
    C = mul(mul(T, mat(c, 9)), [list(r) for r in zip(*T)])
    perm = [0, 1, 2, 6, 7, 8, 3, 4, 5]
    C = [[C[i][j] for j in perm] for i in perm]
    print(f"{g:<9} {s:<9} {rel(R, d['delta_R']):9.1e} {rel(v, d['delta_v']):9.1e} {rel(p, d['delta_p']):9.1e}"
          f" {rel(C, d['covariance']):9.1e}" + ("   (different discretisations)" if g == "tangent" else ""))
EOF

if command -v valgrind > /dev/null; then
  echo "== instructions per integrateMeasurement call (callgrind, $SAMPLES samples; preint's: tools/instructions.sh)"
  for b in manifold tangent liegroup galilean combined; do
    valgrind --tool=callgrind --callgrind-out-file="$OUT/callgrind.$b" --toggle-collect='*integrate<*' \
      "$OUT/bench" --only "$b" --samples "$SAMPLES" > /dev/null 2>&1
    ir=$(grep -E '^summary:|^totals:' "$OUT/callgrind.$b" | tail -n 1 | awk '{print $2}')
    echo "  $b $((ir / (SAMPLES - 1)))"
  done
else
  echo "== instruction counts skipped (apt-get install valgrind)"
fi

echo "== $ROUNDS rounds (GTSAM: median of $RUNS runs of $SAMPLES samples per backend; preint speed: median of 11)"
: > "$OUT/rounds.tsv"
for r in $(seq 1 "$ROUNDS"); do
  g=$("$OUT/bench" --samples "$SAMPLES" --runs "$RUNS" | tr '\n' ' ')
  o=$("$PREINT" speed --samples "$SAMPLES" --json | python3 -c '
import json, sys
d = json.load(sys.stdin)
print(" ".join("{}.{} {:.2f}".format(s["scheme"], k, s["ns_per_sample"][k])
               for s in d["schemes"] for k in ("deltas", "covariance", "combined")))')
  echo "$g $o" >> "$OUT/rounds.tsv"
  echo "round $r/$ROUNDS, load $(cut -d' ' -f1 /proc/loadavg): $g"
done
python3 - "$OUT/rounds.tsv" <<'EOF'
import statistics, sys
rounds = []
for line in open(sys.argv[1]):
    w = line.split(); rounds.append({w[i]: float(w[i + 1]) for i in range(0, len(w), 2)})
def mmm(xs, f="{:.0f}"):
    return " / ".join(f.format(v) for v in (min(xs), statistics.median(xs), max(xs)))
print(f"\nns per sample, min / median / max over {len(rounds)} rounds, with covariance:")
rows = [("GTSAM Manifold", "manifold"), ("GTSAM Tangent (default)", "tangent"),
        ("GTSAM LieGroup", "liegroup"), ("GTSAM Galilean", "galilean"),
        ("GTSAM Combined (Tangent, 15x15)", "combined"),
        ("preint euler", "euler.covariance"), ("preint midpoint", "midpoint.covariance"),
        ("preint galilean", "galilean.covariance"), ("preint hermite4", "hermite4.covariance"),
        ("preint euler 15x15", "euler.combined"), ("preint midpoint 15x15", "midpoint.combined"),
        ("preint galilean 15x15", "galilean.combined")]
for label, k in rows:
    print(f"  {label:<32} {mmm([r[k] for r in rounds])}")
print("\npreint / GTSAM per round, min / median / max:")
for a, b in [("euler.covariance", "manifold"), ("midpoint.covariance", "tangent"),
             ("galilean.covariance", "galilean"), ("midpoint.combined", "combined"),
             ("euler.combined", "combined")]:
    print(f"  {a:<20} / {b:<9} {mmm([r[a] / r[b] for r in rounds], '{:.3f}')}")
EOF
