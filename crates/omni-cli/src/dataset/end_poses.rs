//! Hand-measured end poses (a tape measure, UMBmark): one row per run, the robot's pose where it stopped
//! in the frame of where it started (x along its start heading, y to its left, the heading turned
//! counter-clockwise). CSV with a header: `run,x_m,y_m,yaw_deg` (`yaw_rad` instead of `yaw_deg`, and `x_mm`,
//! `y_mm` or `x_cm`, `y_cm` are accepted); `run` names the recording (its file name without extension).
//! Lines starting with `#` are comments. A table a spreadsheet wrote with decimal commas separates its cells
//! with `;` (`cw-1;0,012;-0,03;1,5`): read so; a decimal comma in a `,`-separated table makes more cells than
//! the header names, which is refused. See docs/formats.md, "Measured end poses".

use super::DatasetError;
use omni_kin::Pose2;
use std::path::Path;

/// One measured end pose.
#[derive(Clone, Debug, PartialEq)]
pub struct EndPose {
    /// The run (recording) it was measured for.
    pub run: String,
    /// The pose where the run stopped, in its start's frame.
    pub pose: Pose2,
    /// Its line in the file (1-based), for messages.
    pub line: usize,
    /// The columns its values were read from, as the header names them (`x_mm`, `yaw_deg`): what a check
    /// against the wheels names when a value looks like another unit.
    pub columns: Columns,
}

/// The header's names of the position and heading columns.
#[derive(Clone, Debug, PartialEq)]
pub struct Columns {
    /// `x_m`, `x_cm` or `x_mm` (`y_…` alike), and its metres per unit.
    pub length: String,
    /// Metres per unit of the length columns.
    pub metres_per_unit: f64,
    /// `yaw_deg` or `yaw_rad`.
    pub yaw: String,
}

/// The length columns accepted, with their metres per unit.
const LENGTHS: [(&str, f64); 3] = [("_m", 1.0), ("_cm", 0.01), ("_mm", 0.001)];

/// Reads an end-pose table; errors name the file, the line and the column.
pub fn read(path: &Path) -> Result<Vec<EndPose>, DatasetError> {
    let text = super::read_text(path)?;
    let mut rows = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((header_no, header)) = rows.next() else {
        return Err(DatasetError::file(path, "is empty: expected a header run,x_m,y_m,yaw_deg and one row per run"));
    };
    // A table written with decimal commas separates its cells with semicolons.
    let separator = if header.contains(';') { ';' } else { ',' };
    let names: Vec<&str> = header.split(separator).map(str::trim).collect();
    let find = |name: &str| names.iter().position(|n| *n == name);
    let length = |axis: &str| LENGTHS.iter().find_map(|(suffix, f)| find(&format!("{axis}{suffix}")).map(|i| (i, *f)));
    let angle = find("yaw_deg").map(|i| (i, 1f64.to_radians())).or_else(|| find("yaw_rad").map(|i| (i, 1.0)));
    let (Some(run), Some(x), Some(y), Some(yaw)) = (find("run"), length("x"), length("y"), angle) else {
        return Err(DatasetError::at(
            path,
            format!("line {}", header_no + 1),
            format!("header {header:?}: expected the columns run, x_m, y_m and yaw_deg (or x_mm / x_cm, yaw_rad)"),
        ));
    };
    let mut out: Vec<EndPose> = Vec::new();
    for (no, line) in rows {
        let at = |column: &str| format!("line {}, column {column}", no + 1);
        let cells: Vec<String> = line
            .split(separator)
            .map(|c| if separator == ';' { c.trim().replace(',', ".") } else { c.trim().to_string() })
            .collect();
        if cells.len() > names.len() && cells[names.len()..].iter().any(|c| !c.is_empty()) {
            return Err(DatasetError::at(
                path,
                format!("line {}", no + 1),
                format!(
                    "{line:?} has {} cells but the header names {} columns: a decimal comma (1,5)? Write decimals \
                     with a point (1.5), or separate the cells with semicolons (run;x_m;y_m;yaw_deg) as spreadsheets \
                     do with decimal commas",
                    cells.len(),
                    names.len()
                ),
            ));
        }
        let cell = |i: usize, column: &str| {
            cells.get(i).map(String::as_str).ok_or_else(|| DatasetError::at(path, at(column), "is missing"))
        };
        let number = |(i, f): (usize, f64), column: &str| -> Result<f64, DatasetError> {
            let text = cell(i, column)?;
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v * f),
                _ => Err(DatasetError::at(path, at(column), format!("{text:?} is not a finite number"))),
            }
        };
        let name = cell(run, "run")?.to_string();
        if let Some(first) = out.iter().find(|e| e.run == name) {
            return Err(DatasetError::at(
                path,
                at("run"),
                format!("run {name:?} is measured twice (first on line {}): keep one row per run", first.line),
            ));
        }
        let pose = Pose2::new(number(x, names[x.0])?, number(y, names[y.0])?, number(yaw, names[yaw.0])?);
        let columns = Columns { length: names[x.0].to_string(), metres_per_unit: x.1, yaw: names[yaw.0].to_string() };
        out.push(EndPose { run: name, pose, line: no + 1, columns });
    }
    if out.is_empty() {
        return Err(DatasetError::file(path, "has a header but no rows: one row per run, run,x_m,y_m,yaw_deg"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_text(text: &str) -> Result<Vec<EndPose>, String> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("ends.csv");
        std::fs::write(&p, text).unwrap();
        read(&p).map_err(|e| e.to_string().replace(&p.display().to_string(), "ends.csv"))
    }

    #[test]
    fn rows_in_any_unit_read_as_metres_and_radians() {
        let e = read_text("# UMBmark\nrun,x_mm,y_mm,yaw_deg\ncw-1,12.5,-30,1.5\n\nccw-1, -4 , 8, -90\n").unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!((e[0].run.as_str(), e[0].line), ("cw-1", 3));
        assert!((e[0].pose.x_m - 0.0125).abs() < 1e-15 && (e[0].pose.y_m + 0.03).abs() < 1e-15);
        assert!((e[1].pose.theta_rad + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    }

    #[test]
    fn bad_tables_name_the_line_and_column() {
        let cases = [
            ("", "ends.csv: is empty: expected a header run,x_m,y_m,yaw_deg and one row per run"),
            (
                "run,x,y,yaw\n",
                "ends.csv: line 1: header \"run,x,y,yaw\": expected the columns run, x_m, y_m and yaw_deg (or x_mm / \
                 x_cm, yaw_rad)",
            ),
            ("run,x_m,y_m,yaw_deg\n", "ends.csv: has a header but no rows: one row per run, run,x_m,y_m,yaw_deg"),
            ("run,x_m,y_m,yaw_deg\na,1,2\n", "ends.csv: line 2, column yaw_deg: is missing"),
            ("run,x_m,y_m,yaw_deg\na,1,two,3\n", "ends.csv: line 2, column y_m: \"two\" is not a finite number"),
            (
                "run,x_m,y_m,yaw_deg\na,1,2,3\na,1,2,3\n",
                "ends.csv: line 3, column run: run \"a\" is measured twice (first on line 2): keep one row per run",
            ),
        ];
        for (text, want) in cases {
            assert_eq!(read_text(text).unwrap_err(), want, "{text:?}");
        }
    }
}
