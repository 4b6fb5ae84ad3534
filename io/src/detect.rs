//! [`Format`] and its detection from the file extension and the first lines.

use crate::error::IoError;
use crate::layout::{Column, Delimiter, HeaderUnits, TextLayout, columns_from_header};
use crate::number::parse_scaled_integer;
use crate::reader::ReadOptions;
use crate::units::Units;
use std::fmt;
use std::path::Path;

/// The formats a source can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// EuRoC / ASL `imu0/data.csv`: `t [ns], w [rad/s] ×3, a [m/s²] ×3`, comma separated.
    Euroc,
    /// TUM-VI `imu0/data.csv`: the EuRoC layout.
    TumVi,
    /// UZH-FPV `imu.txt`: `id t [s] w ×3 a ×3`, space separated.
    UzhFpv,
    /// GTSAM's KITTI layout: `Time [s] dt accel ×3 omega ×3`, space separated.
    Kitti,
    /// Any delimited text: columns from `--columns` or the header names, units from the flags
    /// or the header names.
    Delimited,
    /// ROS 1 bag.
    RosBag,
    /// MCAP (ROS 2).
    Mcap,
    /// ROS 2 SQLite bag (`.db3`).
    Db3,
}

impl Format {
    /// Every format, in the order `--format` lists them.
    pub const ALL: [Format; 8] = [
        Format::Euroc,
        Format::TumVi,
        Format::UzhFpv,
        Format::Kitti,
        Format::Delimited,
        Format::RosBag,
        Format::Mcap,
        Format::Db3,
    ];

    /// The `--format` name.
    pub fn name(self) -> &'static str {
        match self {
            Format::Euroc => "euroc",
            Format::TumVi => "tum-vi",
            Format::UzhFpv => "uzh-fpv",
            Format::Kitti => "kitti",
            Format::Delimited => "delimited",
            Format::RosBag => "bag",
            Format::Mcap => "mcap",
            Format::Db3 => "db3",
        }
    }

    /// The fixed text layout of this format (`None` for delimited text and containers).
    pub fn text_layout(self) -> Option<TextLayout> {
        match self {
            Format::Euroc | Format::TumVi => Some(TextLayout::euroc()),
            Format::UzhFpv => Some(TextLayout::uzh_fpv()),
            Format::Kitti => Some(TextLayout::kitti()),
            _ => None,
        }
    }

    /// True for the container formats (bag, MCAP, db3).
    pub fn is_container(self) -> bool {
        matches!(self, Format::RosBag | Format::Mcap | Format::Db3)
    }

    /// The container format of the bytes a file starts with: ROS 1 bag (`#ROSBAG V2.0`), MCAP
    /// (`\x89MCAP0\r\n`), SQLite (a ROS 2 `.db3`, `SQLite format 3\0`).
    pub fn from_magic(head: &[u8]) -> Option<Format> {
        if head.starts_with(b"#ROSBAG V2.0") {
            Some(Format::RosBag)
        } else if head.starts_with(b"\x89MCAP0\r\n") {
            Some(Format::Mcap)
        } else if head.starts_with(b"SQLite format 3\0") {
            Some(Format::Db3)
        } else {
            None
        }
    }

    /// The format of the file `path` as far as its name and first bytes tell: a container by
    /// extension, else by [`Format::from_magic`]; `None` for text (decided from its lines).
    pub fn of_file(path: &Path) -> Option<Format> {
        Format::from_extension(path).or_else(|| {
            use std::io::Read;
            let mut head = [0u8; 16];
            let mut f = std::fs::File::open(path).ok()?;
            let n = f.read(&mut head).ok()?;
            Format::from_magic(&head[..n])
        })
    }

    /// The container format an extension names (`.bag`, `.mcap`, `.db3`).
    pub fn from_extension(path: &Path) -> Option<Format> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "bag" => Some(Format::RosBag),
            "mcap" => Some(Format::Mcap),
            "db3" => Some(Format::Db3),
            _ => None,
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim().to_ascii_lowercase();
        let alias = match s.as_str() {
            "asl" => "euroc",
            "tumvi" | "tum_vi" => "tum-vi",
            "uzh" | "uzhfpv" | "uzh_fpv" => "uzh-fpv",
            "csv" | "text" | "txt" => "delimited",
            "rosbag" | "ros1" => "bag",
            other => other,
        };
        Format::ALL
            .into_iter()
            .find(|f| f.name() == alias)
            .ok_or_else(|| {
                let names: Vec<&str> = Format::ALL.iter().map(|f| f.name()).collect();
                format!("unknown format `{s}`; expected one of {}", names.join(", "))
            })
    }
}

/// What detection decided for a text source: format, layout and how each part was decided.
#[derive(Clone, Debug, PartialEq)]
pub struct TextDetection {
    /// The format.
    pub format: Format,
    /// Its layout, units included.
    pub layout: TextLayout,
    /// How the columns and units were decided (for the user to check).
    pub notes: Vec<String>,
}

/// Decides the layout of a text source from its first lines (`head`, in file order) and the
/// options: `--format` or `--columns` when given, else the header's names. Units: the flags,
/// else the header's names, else the format's; a delimited source must state its time unit.
pub fn detect_text(
    head: &[String],
    opts: &ReadOptions,
    source_name: &str,
) -> Result<TextDetection, IoError> {
    let lines: Vec<&str> = head
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect();
    let data = lines.iter().position(|l| is_data_row(l));
    let Some(data) = data else {
        return Err(IoError::Empty {
            source_name: source_name.to_string(),
        });
    };
    let delimiter = opts
        .delimiter
        .unwrap_or_else(|| Delimiter::sniff(lines[data]));
    let header = (data > 0).then(|| lines[data - 1]);
    let from_header = header.and_then(|h| columns_from_header(h, delimiter));
    let mut notes = Vec::new();
    let (format, mut layout, header_units) = match (opts.format, &opts.columns) {
        (Some(f), _) if f.text_layout().is_some() => {
            notes.push(format!("format {f} from --format"));
            let layout = f.text_layout().expect("checked");
            (f, layout, HeaderUnits::default())
        }
        (_, Some(columns)) => {
            notes.push("columns from --columns".to_string());
            let layout = TextLayout {
                delimiter,
                columns: columns.clone(),
                units: Units::SI_NS,
            };
            let units = from_header.map(|(_, u)| u).unwrap_or_default();
            (Format::Delimited, layout, units)
        }
        _ => by_header(from_header, delimiter, lines[data], source_name, &mut notes)?,
    };
    layout.units = units(
        layout.units,
        format,
        header_units,
        opts,
        source_name,
        &mut notes,
    )?;
    Ok(TextDetection {
        format,
        layout,
        notes,
    })
}

/// A line whose first field is a number (not a header or comment).
fn is_data_row(line: &str) -> bool {
    if crate::lines::is_comment(line) {
        return false;
    }
    let mut first = "";
    Delimiter::sniff(line).for_each_field(line, |i, f| {
        if i == 0 {
            first = f;
        }
    });
    first.parse::<f64>().is_ok_and(f64::is_finite)
}

type Decided = (Format, TextLayout, HeaderUnits);

/// The format and layout a header names, or an error asking for `--columns`.
fn by_header(
    from_header: Option<(Vec<Column>, HeaderUnits)>,
    delimiter: Delimiter,
    first_row: &str,
    source_name: &str,
    notes: &mut Vec<String>,
) -> Result<Decided, IoError> {
    if let Some((columns, units)) = from_header {
        let known = [Format::Euroc, Format::UzhFpv, Format::Kitti]
            .into_iter()
            .find(|f| {
                let l = f.text_layout().expect("text formats");
                l.columns == columns
                    && l.delimiter == delimiter
                    && units.time.is_none_or(|t| t == l.units.time)
            });
        let format = known.unwrap_or(Format::Delimited);
        notes.push(format!("format {format}: columns from the header"));
        let layout = TextLayout {
            delimiter,
            columns,
            units: known.map_or(Units::SI_NS, |f| f.text_layout().expect("known").units),
        };
        return Ok((format, layout, units));
    }
    let mut fields = Vec::new();
    delimiter.for_each_field(first_row, |_, f| fields.push(f));
    let ns_epoch = parse_scaled_integer(fields[0], 0).is_some_and(|t| t > 1_000_000_000_000);
    if delimiter == Delimiter::Comma && fields.len() == 7 && ns_epoch {
        notes.push(
            "format euroc: no header; 7 comma-separated columns with integer ns timestamps"
                .to_string(),
        );
        return Ok((Format::Euroc, TextLayout::euroc(), HeaderUnits::default()));
    }
    Err(IoError::format(
        source_name,
        format!(
            "cannot tell which column is which ({} {delimiter}-separated fields, no header naming \
             them); give --columns (e.g. t,wx,wy,wz,ax,ay,az; skip for unused columns) or \
             --format",
            fields.len()
        ),
    ))
}

/// The units: each from the flag, else the header, else the format's own; a delimited source
/// without a stated time unit is an error.
fn units(
    default: Units,
    format: Format,
    header: HeaderUnits,
    opts: &ReadOptions,
    source_name: &str,
    notes: &mut Vec<String>,
) -> Result<Units, IoError> {
    let delimited = format == Format::Delimited;
    let time = match (opts.time_unit, header.time) {
        (Some(t), _) => t,
        (None, Some(t)) => t,
        (None, None) if delimited => {
            return Err(IoError::format(
                source_name,
                "the time unit is not stated (no unit in the header); give --time-unit s, ms, us \
                 or ns",
            ));
        }
        (None, None) => default.time,
    };
    let gyro = opts.gyro_unit.or(header.gyro).unwrap_or(default.gyro);
    let accel = opts.accel_unit.or(header.accel).unwrap_or(default.accel);
    let source = |flag: bool, head: bool| match (flag, head) {
        (true, _) => "flag",
        (false, true) => "header",
        (false, false) if delimited => "assumed",
        _ => "format",
    };
    notes.push(format!(
        "units: time {time} ({}), gyro {gyro} ({}), accel {accel} ({})",
        source(opts.time_unit.is_some(), header.time.is_some()),
        source(opts.gyro_unit.is_some(), header.gyro.is_some()),
        source(opts.accel_unit.is_some(), header.accel.is_some()),
    ));
    Ok(Units { time, gyro, accel })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::{AccelUnit, GyroUnit, TimeUnit};

    fn detect(text: &str, opts: &ReadOptions) -> Result<TextDetection, IoError> {
        let head: Vec<String> = text.lines().map(str::to_string).collect();
        detect_text(&head, opts, "f")
    }

    #[test]
    fn the_known_layouts_by_their_headers() {
        let o = ReadOptions::default();
        let d = detect(
            "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n1403715273262142976,-0.1,0.2,0.0,8.1,-1.0,-2.0",
            &o,
        )
        .unwrap();
        assert_eq!((d.format, d.layout.units), (Format::Euroc, Units::SI_NS));
        let d = detect(
            "# id timestamp ang_vel_x ang_vel_y ang_vel_z lin_acc_x lin_acc_y lin_acc_z\n0 1540822773.2470136 0.1 0.2 0.3 1 2 9.8",
            &o,
        )
        .unwrap();
        assert_eq!((d.format, d.layout.units), (Format::UzhFpv, Units::SI_S));
        let d = detect(
            "Time dt accelX accelY accelZ omegaX omegaY omegaZ\n46536.397971133 1.9 0.8 0.6 10.1 0.006 0.007 0.019",
            &o,
        )
        .unwrap();
        assert_eq!((d.format, d.layout.units), (Format::Kitti, Units::SI_S));
        let d = detect(
            "t_s,gyro_x_deg_s,gyro_y_deg_s,gyro_z_deg_s,acc_x_g,acc_y_g,acc_z_g\n0.0,0.465,-0.450,0.165,-0.007659,-0.000999,-1.016316",
            &o,
        )
        .unwrap();
        assert_eq!(d.format, Format::Delimited);
        assert_eq!(
            d.layout.units,
            Units {
                time: TimeUnit::S,
                gyro: GyroUnit::DegPerS,
                accel: AccelUnit::G
            }
        );
        let d = detect("1403715273262142976,-0.1,0.2,0.0,8.1,-1.0,-2.0", &o).unwrap();
        assert_eq!(d.format, Format::Euroc);
    }

    #[test]
    fn flags_win_and_missing_facts_are_asked_for() {
        let text = "0.0;1;2;3;4;5;6\n0.01;1;2;3;4;5;6";
        let e = detect(text, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("give --columns"), "{e}");
        let mut o = ReadOptions {
            columns: Some(crate::layout::parse_columns("t,ax,ay,az,wx,wy,wz").unwrap()),
            ..Default::default()
        };
        let e = detect(text, &o).unwrap_err().to_string();
        assert!(e.contains("--time-unit"), "{e}");
        o.time_unit = Some(TimeUnit::Ms);
        o.gyro_unit = Some(GyroUnit::DegPerS);
        let d = detect(text, &o).unwrap();
        assert_eq!(d.layout.delimiter, Delimiter::Semicolon);
        assert_eq!(d.layout.units.time, TimeUnit::Ms);
        assert_eq!(d.layout.units.gyro, GyroUnit::DegPerS);
        assert!(
            d.notes.iter().any(|n| n.contains("accel m/s2 (assumed)")),
            "{:?}",
            d.notes
        );
        let o = ReadOptions {
            format: Some(Format::Kitti),
            ..Default::default()
        };
        assert_eq!(
            detect("1 2 3 4 5 6 7 8", &o).unwrap().layout,
            TextLayout::kitti()
        );
        assert!(matches!(
            detect("# only a comment", &ReadOptions::default()),
            Err(IoError::Empty { .. })
        ));
    }
}
