//! The synthetic OptiOdom sets of the `optiodom` tests (included with `#[path]`): a robot type, its metadata
//! values and the robot that made it, written as OptiOdom lays a set out, the ground truth integrated with
//! OptiOdom's own nominal model.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::Path;

/// A synthetic OptiOdom set: robot type and metadata values, and the robot that made it.
pub struct Set {
    pub kind: &'static str,
    pub ngear: f64,
    pub enc_res: f64,
    pub li: Vec<f64>,
    pub di: Vec<f64>,
    pub dt_s: f64,
    /// The robot that made the ground truth: each wheel's arc length scaled by `wheel_gain[i]`, and `li`
    /// replaced by `true_li` in OptiOdom's formulas. Default: the metadata's robot.
    pub wheel_gain: Vec<f64>,
    pub true_li: Vec<f64>,
    /// Wheels driven by a controller from a smooth body twist through the nominal model (a real robot:
    /// they never fight each other) instead of each wheel on its own.
    pub from_twist: bool,
    /// Added to each run's index to vary its motion (held-out sets).
    pub seed_offset: usize,
}

impl Set {
    pub fn new(kind: &'static str, ngear: f64, enc_res: f64, li: &[f64], di: &[f64], dt_s: f64) -> Self {
        let (li, di) = (li.to_vec(), di.to_vec());
        let (wheel_gain, true_li) = (vec![1.0; di.len()], li.clone());
        Self { kind, ngear, enc_res, li, di, dt_s, wheel_gain, true_li, from_twist: false, seed_offset: 0 }
    }
    pub fn omni4() -> Self {
        Self::new("omni4", 1.0, 1.0, &[0.205, 0.215], &[0.06, 0.0592, 0.0607, 0.06], 0.01)
    }
    pub fn diff() -> Self {
        Self::new("diff", 43.7, 64.0, &[0.2], &[0.084, 0.0832], 0.05)
    }
    pub fn omni3() -> Self {
        Self::new("omni3", 12.0, 1024.0, &[0.195], &[0.102, 0.1, 0.103], 0.04)
    }

    /// The same set made by a robot whose wheels roll `wheel_gain` × their nominal arc and whose `Li` is
    /// `true_li`, its wheels driven from a body twist.
    pub fn real(mut self, wheel_gain: &[f64], true_li: &[f64]) -> Self {
        self.wheel_gain = wheel_gain.to_vec();
        self.true_li = true_li.to_vec();
        self.from_twist = true;
        self
    }

    /// OptiOdom's robot-frame displacement (dx m, dy m, dθ rad) of one cycle from the wheel arc lengths
    /// (m), with wheel-position values `li`: the README formulas, written out independently of the reader.
    pub fn model(&self, s: &[f64], li: &[f64]) -> [f64; 3] {
        match self.kind {
            "omni3" => {
                let l = li[0];
                let r3 = 3f64.sqrt() / 3.0;
                [r3 * (s[1] - s[0]), (2.0 * s[2] - s[0] - s[1]) / 3.0, -(s[0] + s[1] + s[2]) / (3.0 * l)]
            }
            "omni4" => {
                let k = -1.0 / (2.0 * (li[0] + li[1]));
                [(s[0] - s[1] + s[2] - s[3]) / 4.0, (-s[0] - s[1] + s[2] + s[3]) / 4.0, k * (s[0] + s[1] + s[2] + s[3])]
            }
            "diff" => [(s[0] + s[1]) / 2.0, 0.0, (s[0] - s[1]) / li[0]],
            k => panic!("no nominal model for {k}"),
        }
    }

    /// The nominal wheel arcs (m) that make the body displacement `d` (dx m, dy m, dθ rad): the exact
    /// inverse of [`Self::model`] with the metadata's `li` (omni4's forward rows are orthogonal).
    pub fn arcs(&self, d: [f64; 3]) -> Vec<f64> {
        match self.kind {
            "omni4" => {
                let c = (self.li[0] + self.li[1]) / 2.0;
                let signs = [(1.0, -1.0), (-1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                signs.iter().map(|(a, b)| a * d[0] + b * d[1] - c * d[2]).collect()
            }
            "diff" => vec![d[0] + self.li[0] / 2.0 * d[2], d[0] - self.li[0] / 2.0 * d[2]],
            k => panic!("no forward model for {k}"),
        }
    }

    /// Writes `<dir>/<id>/` with a metadata file and `runs` run files; returns the set folder.
    pub fn write(&self, dir: &Path, id: &str, runs: usize) -> std::path::PathBuf {
        let set = dir.join(id);
        std::fs::create_dir_all(&set).unwrap();
        let row =
            |k: &str, v: &[f64]| format!("{k},{}\n", v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(","));
        let mut meta = format!("type,{},,\n", self.kind);
        meta += &row("ngear", &[self.ngear]);
        meta += &row("encRes", &[self.enc_res]);
        meta += &row("Li", &self.li);
        meta += &row("Di", &self.di);
        meta += "Thi,,,\n";
        meta += &row("N", &[runs as f64]);
        std::fs::write(set.join(format!("{id}_metadata.csv")), meta).unwrap();
        for r in 0..runs {
            std::fs::write(set.join(format!("{id}_run-{:02}.csv", r + 1)), self.run_text(r + self.seed_offset))
                .unwrap();
        }
        set
    }

    /// Nominal wheel arcs (m) of cycle `k` of run `seed`: each wheel on its own (smoothly varying, its own
    /// frequency and phase), or from a smooth body twist ([`Self::from_twist`]).
    pub fn cycle_arcs(&self, k: usize, seed: usize) -> Vec<f64> {
        let (t, sd) = (k as f64 * self.dt_s, seed as f64);
        if self.from_twist {
            let wave = |f: f64, phase: f64| (2.0 * PI * f * t + phase + sd).sin();
            let vy = if self.kind == "diff" { 0.0 } else { 0.25 * wave(0.11, 2.0) };
            let twist = [0.3 * wave(0.13, 0.0), vy, 0.9 * wave(0.07 + 0.02 * sd, 1.0)];
            return self.arcs(twist.map(|v| v * self.dt_s));
        }
        (0..self.di.len())
            .map(|i| {
                let f = 0.3 + 0.17 * i as f64 + 0.05 * sd;
                let speed_m_s = 0.3 * (2.0 * PI * f * t + i as f64 + sd).sin() + 0.1 * (i as f64 - 1.0);
                speed_m_s * self.dt_s
            })
            .collect()
    }

    /// One run: 6 s of wheel motion ([`Self::cycle_arcs`]), the ground truth integrated from it with the
    /// true robot's model held over each cycle (an exact arc).
    pub fn run_text(&self, seed: usize) -> String {
        let n = self.di.len();
        let per_tick: Vec<f64> = self.di.iter().map(|d| PI * d / (self.ngear * self.enc_res)).collect();
        let cycles = (6.0 / self.dt_s).round() as usize;
        let (mut x, mut y, mut th) = (0.0f64, 0.0f64, 0.0f64);
        let mut text = String::new();
        for k in 0..=cycles {
            let t = k as f64 * self.dt_s;
            let arcs = if k == 0 { vec![0.0; n] } else { self.cycle_arcs(k, seed) };
            let ticks: Vec<f64> = (0..n).map(|i| arcs[i] / per_tick[i]).collect();
            let s: Vec<f64> = (0..n).map(|i| self.wheel_gain[i] * per_tick[i] * ticks[i]).collect();
            let [dx, dy, a] = self.model(&s, &self.true_li);
            let (f1, f2) =
                if a.abs() < 1e-6 { (1.0 - a * a / 6.0, a / 2.0) } else { (a.sin() / a, (1.0 - a.cos()) / a) };
            let (bx, by) = (f1 * dx - f2 * dy, f2 * dx + f1 * dy);
            let (sn, cs) = th.sin_cos();
            x += cs * bx - sn * by;
            y += sn * bx + cs * by;
            th += a;
            write!(text, "{t},{x},{y},{th}").unwrap();
            for v in &ticks {
                write!(text, ",{v}").unwrap();
            }
            text.push('\n');
        }
        text
    }
}
