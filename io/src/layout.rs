//! The layout of a delimited text source: delimiter, which column holds what, and units.
//! Also the header-name rules that recognise columns such as `gyro_x_deg_s`, `acc_z_g`,
//! `t_s`, `w_RS_S_x [rad s^-1]`, `omegaX` or `lin_acc_y`.

use crate::units::{AccelUnit, GyroUnit, TimeUnit, Units};
use std::fmt;

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// Timestamp.
    T,
    /// Gyroscope x, y, z.
    Wx,
    /// Gyroscope y.
    Wy,
    /// Gyroscope z.
    Wz,
    /// Accelerometer x.
    Ax,
    /// Accelerometer y.
    Ay,
    /// Accelerometer z.
    Az,
    /// A column that is not read.
    Skip,
}

/// The seven columns a sample needs, in the order of [`TextLayout::positions`].
pub const SAMPLE_COLUMNS: [Column; 7] = [
    Column::T,
    Column::Wx,
    Column::Wy,
    Column::Wz,
    Column::Ax,
    Column::Ay,
    Column::Az,
];

impl Column {
    fn name(self) -> &'static str {
        match self {
            Column::T => "t",
            Column::Wx => "wx",
            Column::Wy => "wy",
            Column::Wz => "wz",
            Column::Ax => "ax",
            Column::Ay => "ay",
            Column::Az => "az",
            Column::Skip => "skip",
        }
    }
}

/// Parses a `--columns` list such as `t,ax,ay,az,wx,wy,wz` or `skip,t,wx,wy,wz,ax,ay,az`
/// (`gx, gy, gz` are accepted for the gyro, `time` for `t`, `_` for `skip`). Each of the seven
/// sample columns must appear exactly once.
pub fn parse_columns(spec: &str) -> Result<Vec<Column>, String> {
    let columns = spec
        .split(',')
        .map(|c| match c.trim().to_ascii_lowercase().as_str() {
            "t" | "time" => Ok(Column::T),
            "wx" | "gx" => Ok(Column::Wx),
            "wy" | "gy" => Ok(Column::Wy),
            "wz" | "gz" => Ok(Column::Wz),
            "ax" => Ok(Column::Ax),
            "ay" => Ok(Column::Ay),
            "az" => Ok(Column::Az),
            "skip" | "_" => Ok(Column::Skip),
            other => Err(format!(
                "unknown column `{other}` in --columns `{spec}`; expected t, wx, wy, wz, ax, ay, \
                 az or skip"
            )),
        })
        .collect::<Result<Vec<_>, _>>()?;
    for want in SAMPLE_COLUMNS {
        let n = columns.iter().filter(|&&c| c == want).count();
        if n != 1 {
            return Err(format!(
                "--columns `{spec}` names `{}` {n} times; each of t, wx, wy, wz, ax, ay, az must \
                 appear exactly once",
                want.name()
            ));
        }
    }
    Ok(columns)
}

/// How fields are separated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Delimiter {
    /// `,`
    Comma,
    /// `;`
    Semicolon,
    /// A tab.
    Tab,
    /// Any run of spaces and tabs.
    Whitespace,
}

impl Delimiter {
    /// The delimiter of a data line: the first of `,`, `;`, tab that occurs, else whitespace.
    pub fn sniff(line: &str) -> Delimiter {
        if line.contains(',') {
            Delimiter::Comma
        } else if line.contains(';') {
            Delimiter::Semicolon
        } else if line.contains('\t') && !line.trim().contains(' ') {
            Delimiter::Tab
        } else {
            Delimiter::Whitespace
        }
    }

    /// Calls `f(index, field)` for each trimmed field of `line`, a field in double quotes
    /// without them (RFC 4180 quoting, as spreadsheet exports write numbers; a quoted field
    /// holding the delimiter is not supported: numbers never do); returns the number of fields.
    #[inline]
    pub fn for_each_field<'a>(self, line: &'a str, mut f: impl FnMut(usize, &'a str)) -> usize {
        let mut n = 0;
        let mut visit = |s: &'a str| {
            f(n, unquote(s.trim_ascii()));
            n += 1;
        };
        match self {
            Delimiter::Comma => split_at_byte(line, b',', &mut visit),
            Delimiter::Semicolon => split_at_byte(line, b';', &mut visit),
            Delimiter::Tab => split_at_byte(line, b'\t', &mut visit),
            Delimiter::Whitespace => line.split_ascii_whitespace().for_each(&mut visit),
        }
        n
    }
}

/// `field` without one pair of enclosing double quotes (and the blanks inside them).
#[inline]
fn unquote(field: &str) -> &str {
    match field.as_bytes() {
        [b'"', .., b'"'] if field.len() >= 2 => field[1..field.len() - 1].trim_ascii(),
        _ => field,
    }
}

/// The fields of `line` between the ASCII bytes `delimiter`, in order (as `str::split`, with a
/// byte loop: the fields of an IMU row are a few bytes long, shorter than a vectorised search
/// needs to pay off).
#[inline]
fn split_at_byte<'a>(line: &'a str, delimiter: u8, visit: &mut impl FnMut(&'a str)) {
    let mut start = 0;
    for (i, &b) in line.as_bytes().iter().enumerate() {
        if b == delimiter {
            // An ASCII byte is always a char boundary.
            visit(&line[start..i]);
            start = i + 1;
        }
    }
    visit(&line[start..]);
}

impl fmt::Display for Delimiter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Delimiter::Comma => "comma",
            Delimiter::Semicolon => "semicolon",
            Delimiter::Tab => "tab",
            Delimiter::Whitespace => "whitespace",
        })
    }
}

impl std::str::FromStr for Delimiter {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "," | "comma" => Ok(Delimiter::Comma),
            ";" | "semicolon" => Ok(Delimiter::Semicolon),
            "\t" | "\\t" | "tab" => Ok(Delimiter::Tab),
            " " | "space" | "whitespace" => Ok(Delimiter::Whitespace),
            other => Err(format!(
                "unknown delimiter `{other}`; expected comma, semicolon, tab or whitespace"
            )),
        }
    }
}

/// Delimiter, columns and units of a text source.
#[derive(Clone, Debug, PartialEq)]
pub struct TextLayout {
    /// Field separator.
    pub delimiter: Delimiter,
    /// What each column holds, in file order; rows must have exactly this many fields.
    pub columns: Vec<Column>,
    /// Units of the time, gyro and accelerometer columns.
    pub units: Units,
}

impl TextLayout {
    /// EuRoC / ASL `imu0/data.csv` (also TUM-VI): `t [ns], w_x, w_y, w_z [rad/s], a_x, a_y,
    /// a_z [m/s²]`.
    pub fn euroc() -> Self {
        Self {
            delimiter: Delimiter::Comma,
            columns: SAMPLE_COLUMNS.to_vec(),
            units: Units::SI_NS,
        }
    }

    /// UZH-FPV `imu.txt`: `id t [s] w_x w_y w_z [rad/s] a_x a_y a_z [m/s²]`, space separated.
    pub fn uzh_fpv() -> Self {
        let mut columns = vec![Column::Skip];
        columns.extend(SAMPLE_COLUMNS);
        Self {
            delimiter: Delimiter::Whitespace,
            columns,
            units: Units::SI_S,
        }
    }

    /// GTSAM's KITTI file (`KittiEquivBiasedImu.txt`): `Time [s] dt accelX accelY accelZ
    /// [m/s²] omegaX omegaY omegaZ [rad/s]`, space separated.
    pub fn kitti() -> Self {
        use Column::*;
        Self {
            delimiter: Delimiter::Whitespace,
            columns: vec![T, Skip, Ax, Ay, Az, Wx, Wy, Wz],
            units: Units::SI_S,
        }
    }

    /// The column index of each of [`SAMPLE_COLUMNS`] (t, wx, wy, wz, ax, ay, az).
    pub fn positions(&self) -> [usize; 7] {
        SAMPLE_COLUMNS.map(|want| {
            self.columns
                .iter()
                .position(|&c| c == want)
                .expect("layouts name every sample column")
        })
    }

    /// The columns as a `--columns` list.
    pub fn columns_spec(&self) -> String {
        let names: Vec<&str> = self.columns.iter().map(|c| c.name()).collect();
        names.join(",")
    }
}

/// Units a header names; `None` where it names none.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HeaderUnits {
    /// From the time column's name (`t_s`, `timestamp [ns]`).
    pub time: Option<TimeUnit>,
    /// From the gyro columns' names (`_deg_s`, `[rad s^-1]`).
    pub gyro: Option<GyroUnit>,
    /// From the accelerometer columns' names (`_g`, `[m s^-2]`).
    pub accel: Option<AccelUnit>,
}

/// Lower-case words of a header field, split at non-alphanumerics and lower→upper case changes
/// (`w_RS_S_x [rad s^-1]` → `w rs s x rad s 1`, `accelX` → `accel x`).
pub(crate) fn words(field: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    let mut prev_lower = false;
    for ch in field.chars() {
        let split = !ch.is_alphanumeric() || (ch.is_uppercase() && prev_lower);
        if split && !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
        if ch.is_alphanumeric() {
            cur.extend(ch.to_lowercase());
        }
        prev_lower = ch.is_lowercase() || ch.is_ascii_digit();
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// What one header field names: its column, and a unit if it states one.
fn classify(field: &str) -> (Column, HeaderUnits) {
    let w = words(field);
    let mut units = HeaderUnits::default();
    let Some(first) = w.first().map(String::as_str) else {
        return (Column::Skip, units);
    };
    let has = |s: &str| w.iter().skip(1).any(|x| x == s);
    if matches!(first, "t" | "time" | "timestamp" | "stamp" | "ts") {
        units.time = if has("ns") {
            Some(TimeUnit::Ns)
        } else if has("us") {
            Some(TimeUnit::Us)
        } else if has("ms") {
            Some(TimeUnit::Ms)
        } else if has("s") || has("sec") {
            Some(TimeUnit::S)
        } else {
            None
        };
        return (Column::T, units);
    }
    let axis = w
        .iter()
        .skip(1)
        .find_map(|x| ["x", "y", "z"].iter().position(|a| a == x));
    let single = ["wx", "wy", "wz", "gx", "gy", "gz", "ax", "ay", "az"]
        .iter()
        .position(|s| *s == first);
    let gyro_word = matches!(
        first,
        "gyro" | "gyr" | "gyroscope" | "omega" | "w" | "ang" | "angular"
    );
    let acc_word = matches!(
        first,
        "acc" | "accel" | "accelerometer" | "acceleration" | "a" | "lin" | "linear"
    );
    let column = match (single, gyro_word, acc_word, axis) {
        (Some(i), ..) => [Column::Wx, Column::Wy, Column::Wz][i % 3].with_kind(i >= 6),
        (None, true, _, Some(a)) => [Column::Wx, Column::Wy, Column::Wz][a],
        (None, _, true, Some(a)) => [Column::Ax, Column::Ay, Column::Az][a],
        _ => Column::Skip,
    };
    match column {
        Column::Wx | Column::Wy | Column::Wz => {
            units.gyro = if has("deg") || has("dps") {
                Some(GyroUnit::DegPerS)
            } else if has("rad") {
                Some(GyroUnit::RadPerS)
            } else {
                None
            };
        }
        Column::Ax | Column::Ay | Column::Az => {
            units.accel = if has("g") {
                Some(AccelUnit::G)
            } else if has("m") {
                Some(AccelUnit::MPerS2)
            } else {
                None
            };
        }
        _ => {}
    }
    (column, units)
}

impl Column {
    /// The accelerometer column of the same axis when `accel`, else `self`.
    fn with_kind(self, accel: bool) -> Column {
        match (self, accel) {
            (Column::Wx, true) => Column::Ax,
            (Column::Wy, true) => Column::Ay,
            (Column::Wz, true) => Column::Az,
            (c, _) => c,
        }
    }
}

/// The columns and units a header line (a leading `#` allowed) names, split at `delimiter`,
/// if it names each sample column exactly once.
pub fn columns_from_header(line: &str, delimiter: Delimiter) -> Option<(Vec<Column>, HeaderUnits)> {
    let line = line.trim_start().trim_start_matches('#');
    let mut fields = Vec::new();
    delimiter.for_each_field(line, |_, f| fields.push(f));
    let mut columns = Vec::with_capacity(fields.len());
    let mut units = HeaderUnits::default();
    for f in fields {
        let (c, u) = classify(f);
        if c != Column::Skip && columns.contains(&c) {
            return None;
        }
        units.time = units.time.or(u.time);
        units.gyro = units.gyro.or(u.gyro);
        units.accel = units.accel.or(u.accel);
        columns.push(c);
    }
    SAMPLE_COLUMNS
        .iter()
        .all(|c| columns.contains(c))
        .then_some((columns, units))
}

#[cfg(test)]
mod tests {
    use super::*;
    use Column::*;

    fn header(line: &str) -> Option<(Vec<Column>, HeaderUnits)> {
        columns_from_header(line, Delimiter::sniff(line))
    }

    #[test]
    fn headers_of_real_recordings() {
        let (c, u) = header(
            "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],\
             a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]",
        )
        .unwrap();
        assert_eq!(c, SAMPLE_COLUMNS);
        assert_eq!(
            (u.time, u.gyro, u.accel),
            (
                Some(TimeUnit::Ns),
                Some(GyroUnit::RadPerS),
                Some(AccelUnit::MPerS2)
            )
        );
        let (c, u) =
            header("t_s,gyro_x_deg_s,gyro_y_deg_s,gyro_z_deg_s,acc_x_g,acc_y_g,acc_z_g").unwrap();
        assert_eq!(c, SAMPLE_COLUMNS);
        assert_eq!(
            (u.time, u.gyro, u.accel),
            (
                Some(TimeUnit::S),
                Some(GyroUnit::DegPerS),
                Some(AccelUnit::G)
            )
        );
        let (c, u) = header(
            "t_s,gyr_x_rad_s,gyr_y_rad_s,gyr_z_rad_s,acc_x_m_s2,acc_y_m_s2,acc_z_m_s2,opt_qw,\
             opt_qx,opt_qy,opt_qz,opt_px_m,opt_py_m,opt_pz_m,movement",
        )
        .unwrap();
        assert_eq!(&c[..7], SAMPLE_COLUMNS);
        assert!(c[7..].iter().all(|&x| x == Skip));
        assert_eq!(u.accel, Some(AccelUnit::MPerS2));
        let (c, u) = header("Time dt accelX accelY accelZ omegaX omegaY omegaZ").unwrap();
        assert_eq!(c, [T, Skip, Ax, Ay, Az, Wx, Wy, Wz]);
        assert_eq!(u, HeaderUnits::default());
        let (c, _) =
            header("# id timestamp ang_vel_x ang_vel_y ang_vel_z lin_acc_x lin_acc_y lin_acc_z")
                .unwrap();
        assert_eq!(c, [Skip, T, Wx, Wy, Wz, Ax, Ay, Az]);
        let (c, _) = header("time;ax;ay;az;gx;gy;gz").unwrap();
        assert_eq!(c, [T, Ax, Ay, Az, Wx, Wy, Wz]);
    }

    #[test]
    fn ambiguous_or_incomplete_headers_name_nothing() {
        assert!(header("t,wx,wy,wz,ax,ay").is_none());
        assert!(header("t,wx,wy,wz,ax,ay,az,ax").is_none());
        assert!(header("a,b,c,d,e,f,g").is_none());
    }

    #[test]
    fn columns_flag() {
        assert_eq!(
            parse_columns("t,ax,ay,az,wx,wy,wz").unwrap(),
            [T, Ax, Ay, Az, Wx, Wy, Wz]
        );
        assert_eq!(
            parse_columns("skip, time, gx, gy, gz, ax, ay, az, _").unwrap(),
            [Skip, T, Wx, Wy, Wz, Ax, Ay, Az, Skip]
        );
        let e = parse_columns("t,ax,ay,az,wx,wy").unwrap_err();
        assert!(e.contains("`wz` 0 times"), "{e}");
        let e = parse_columns("t,ax,ay,az,wx,wy,wz,q").unwrap_err();
        assert!(e.contains("unknown column `q`"), "{e}");
    }
}
