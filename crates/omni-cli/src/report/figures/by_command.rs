//! The end position errors per (α, ω) command, as the flower and the heat map draw them.

use crate::report::Report;

/// Distinct values, rounded to `tol`, in increasing order.
fn distinct(values: impl IntoIterator<Item = f64>, tol: f64) -> Vec<f64> {
    let mut v: Vec<f64> = Vec::new();
    for x in values {
        if !v.iter().any(|y| (x - y).abs() < tol) {
            v.push(x);
        }
    }
    v.sort_by(f64::total_cmp);
    v
}

/// Mean end position error (m) per model for each (α, ω) command.
pub(super) fn by_command(r: &Report) -> (Vec<f64>, Vec<f64>, Vec<Vec<Vec<f64>>>) {
    let alphas = distinct(r.runs.iter().filter_map(|x| x.alpha_rad.map(|a| a.rem_euclid(std::f64::consts::TAU))), 1e-3);
    let omegas = distinct(r.runs.iter().filter_map(|x| x.omega_rad_s), 1e-3);
    let nm = r.models.len();
    let mut sum = vec![vec![vec![(0.0, 0usize); alphas.len()]; omegas.len()]; nm];
    for x in &r.runs {
        let (Some(a), Some(w)) = (x.alpha_rad, x.omega_rad_s) else { continue };
        let a = a.rem_euclid(std::f64::consts::TAU);
        let (Some(ia), Some(iw)) =
            (alphas.iter().position(|v| (v - a).abs() < 1e-3), omegas.iter().position(|v| (v - w).abs() < 1e-3))
        else {
            continue;
        };
        for (m, e) in x.end_position_m.iter().enumerate() {
            sum[m][iw][ia].0 += e;
            sum[m][iw][ia].1 += 1;
        }
    }
    let mean = sum
        .into_iter()
        .map(|w| {
            w.into_iter()
                .map(|a| a.into_iter().map(|(s, n)| if n == 0 { f64::NAN } else { s / n as f64 }).collect())
                .collect()
        })
        .collect();
    (alphas, omegas, mean)
}
