//! What to read and how: the file or folder, a forced clock offset, and a CSV file's column names and units
//! (`--gt-columns`, `--gt-units`, `[ground_truth]` in robot.toml).

use std::path::PathBuf;

/// Ground truth from files.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GroundTruthOptions {
    /// A file (one recording) or a folder of files named after the recordings.
    pub path: PathBuf,
    /// Force the clock offset `t_wheel = t_truth + offset` instead of estimating it. s. Default: estimated.
    pub time_offset_s: Option<f64>,
    /// CSV column names and units.
    pub csv: CsvColumns,
}

/// Time units of a CSV time column.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    #[default]
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl TimeUnit {
    pub(super) fn ns(self) -> i64 {
        match self {
            Self::S => 1_000_000_000,
            Self::Ms => 1_000_000,
            Self::Us => 1_000,
            Self::Ns => 1,
        }
    }
}

/// A ground-truth column or unit the CSV reader does not know (`--gt-columns`, `--gt-units`,
/// `[ground_truth]` in robot.toml).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CsvColumnsError {
    /// A column key other than `t`, `x`, `y` or `yaw`.
    #[error("unknown ground-truth column {key:?} (expected t, x, y or yaw)")]
    UnknownColumn {
        /// The key given.
        key: String,
    },
    /// A unit key or unit other than those of [`CsvColumns::set_unit`].
    #[error("unknown ground-truth unit {key}={unit} (expected time=s|ms|us|ns, length=m|cm|mm, angle=rad|deg)")]
    UnknownUnit {
        /// The key given.
        key: String,
        /// The unit given.
        unit: String,
    },
}

/// CSV column names and units.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvColumns {
    /// Time column. Default `t`.
    pub t: String,
    /// x column. Default `x`.
    pub x: String,
    /// y column. Default `y`.
    pub y: String,
    /// Heading column; when the header has no such column, a quaternion `qx`, `qy`, `qz`, `qw` is read, and
    /// when it has neither, or this is [`CsvColumns::NO_HEADING`], the file gives positions only.
    /// Default `yaw`.
    pub yaw: String,
    /// Unit of the time column. Default s.
    pub time_unit: TimeUnit,
    /// Metres per unit of x and y (1 for m, 0.001 for mm). Default 1.
    pub m_per_length_unit: f64,
    /// Radians per unit of the heading (1 for rad, π/180 for deg). Default 1.
    pub rad_per_angle_unit: f64,
}

impl Default for CsvColumns {
    fn default() -> Self {
        Self {
            t: "t".into(),
            x: "x".into(),
            y: "y".into(),
            yaw: "yaw".into(),
            time_unit: TimeUnit::S,
            m_per_length_unit: 1.0,
            rad_per_angle_unit: 1.0,
        }
    }
}

impl CsvColumns {
    /// The heading column's name for a file without a heading (`--gt-columns yaw=none`, or a list of
    /// columns without `yaw`: `--gt-columns t,x,y`).
    pub const NO_HEADING: &'static str = "none";

    /// Sets a column name: `t`, `x`, `y` or `yaw` (as in `--gt-columns t=stamp_ns`).
    pub fn set_column(&mut self, key: &str, name: &str) -> Result<(), CsvColumnsError> {
        let slot = match key {
            "t" | "time" => &mut self.t,
            "x" => &mut self.x,
            "y" => &mut self.y,
            "yaw" => &mut self.yaw,
            _ => return Err(CsvColumnsError::UnknownColumn { key: key.to_string() }),
        };
        *slot = name.to_string();
        Ok(())
    }

    /// Sets a unit: `time` (s, ms, us, ns), `length` (m, cm, mm) or `angle` (rad, deg).
    pub fn set_unit(&mut self, key: &str, unit: &str) -> Result<(), CsvColumnsError> {
        match (key, unit) {
            ("time", "s") => self.time_unit = TimeUnit::S,
            ("time", "ms") => self.time_unit = TimeUnit::Ms,
            ("time", "us") => self.time_unit = TimeUnit::Us,
            ("time", "ns") => self.time_unit = TimeUnit::Ns,
            ("length", "m") => self.m_per_length_unit = 1.0,
            ("length", "cm") => self.m_per_length_unit = 0.01,
            ("length", "mm") => self.m_per_length_unit = 0.001,
            ("angle", "rad") => self.rad_per_angle_unit = 1.0,
            ("angle", "deg") => self.rad_per_angle_unit = std::f64::consts::PI / 180.0,
            _ => return Err(CsvColumnsError::UnknownUnit { key: key.to_string(), unit: unit.to_string() }),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_columns_and_units_are_refused_with_what_is_expected() {
        let mut c = CsvColumns::default();
        assert_eq!(
            c.set_column("z", "height").unwrap_err().to_string(),
            "unknown ground-truth column \"z\" (expected t, x, y or yaw)"
        );
        assert_eq!(
            c.set_unit("length", "in").unwrap_err().to_string(),
            "unknown ground-truth unit length=in (expected time=s|ms|us|ns, length=m|cm|mm, angle=rad|deg)"
        );
        assert_eq!(c, CsvColumns::default());
    }
}
