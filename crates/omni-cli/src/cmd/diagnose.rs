//! `omnical diagnose`: compare, locate, and name the missing effect; `--auto` climbs the error ladder.

use super::{DataArgs, OutputArgs};
use crate::api::ModelSpec;
use crate::api::diagnose::{DiagnoseRequest, diagnose_loaded};
use crate::cli::effect_help;
use crate::units::{std_error_text, value_text};
use omni_ga::diagnose::{DiagnoseOptions, Diagnosis, Finding};
use omni_ga::explore::Exploration;
use omni_ga::identify::Advice;
use omni_ga::science::text;
use std::path::PathBuf;

/// Arguments of `omnical diagnose`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (from `train --out`) or `design`.
    #[arg(long)]
    pub model: ModelSpec,
    /// Training runs (the ones the model was fitted on).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Held-out runs: a file or folder; repeat for more (`--validate A --validate B`). Default: 2-fold
    /// cross-validation over repetitions.
    #[arg(long, value_name = "PATH")]
    pub validate: Vec<PathBuf>,
    /// Add effects one at a time while the held-out cost falls, and print the error ladder; with
    /// --validate, then run the explorer and name the family it passes.
    #[arg(long)]
    pub auto: bool,
    /// Candidate effects (effect ids, comma-separated; default: all of them).
    #[arg(long, value_delimiter = ',', value_name = "NAMES", help = effect_help(
        "Candidate effects, comma-separated (default: all of them)."
    ))]
    pub candidates: Vec<String>,
    /// Minimum relative fall of the held-out path cost to recommend an effect.
    #[arg(long, default_value_t = DiagnoseOptions::default().min_gain)]
    pub min_gain: f64,
    /// Write the final model (with the effects and the explorer's family added by --auto) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Output options (JSON: top-level `verdict`, `ranking`, `ladder`, …).
    #[command(flatten)]
    pub output: OutputArgs,
    /// Data options.
    #[command(flatten)]
    pub data: DataArgs,
}

impl Args {
    /// What these flags ask `omnical diagnose` to do.
    pub fn request(&self) -> DiagnoseRequest {
        let mut options = DiagnoseOptions { auto: self.auto, min_gain: self.min_gain, ..DiagnoseOptions::default() };
        if !self.candidates.is_empty() {
            options.candidates = self.candidates.clone();
        }
        DiagnoseRequest {
            model: self.model.clone(),
            runs: self.runs.clone(),
            validate: self.validate.clone(),
            data: self.data.options(),
            options,
            out: self.out.clone(),
        }
    }
}

/// Runs `omnical diagnose`.
pub fn run(a: &Args) -> anyhow::Result<()> {
    let (d, _) = diagnose_loaded(&a.request())?;
    // `--auto` with held-out runs ran the explorer from the ladder's model; `--out` holds the final model,
    // with the family it passed.
    let exploration = d.exploration.as_ref();
    if a.output.json {
        let mut doc = serde_json::to_value(&d)?;
        if let Some(e) = exploration {
            doc["explore"] = crate::api::explore::to_json(e);
        }
        doc["out"] =
            serde_json::json!(a.out.as_ref().filter(|_| d.final_model.is_some()).map(|p| p.display().to_string()));
        super::print_json("diagnose", doc)?;
    } else {
        print_diagnosis(&d);
        if a.auto {
            print_explore_stage(exploration);
        }
        if let (Some(out), Some(x)) = (&a.out, &d.conclusion.explored) {
            println!(
                "model written to {} (the ladder's model with {}, which the explorer passed)",
                out.display(),
                x.effect
            );
        }
    }
    Ok(())
}

/// The explorer stage in text: the ranking and the best family's hint (or why it did not run).
fn print_explore_stage(e: Option<&Exploration>) {
    let Some(e) = e else {
        println!("5. explore: skipped (the explorer judges families on held-out runs: give --validate)");
        return;
    };
    println!("5. explore: beyond the catalogue (families fitted on the training runs, judged on the held-out runs)");
    let lines = text::exploration(e);
    let (conclusion, ranking) = lines.split_last().map_or((None, &lines[..]), |(c, r)| (Some(c), r));
    for l in ranking {
        println!("   {l}");
    }
    if let Some(best) = e.best() {
        println!("   best: learned:{}: {}", best.family.id(), text::explore_hint(best));
    }
    if let Some(c) = conclusion {
        println!("   {c}");
    }
}

/// Human-readable diagnosis.
///
/// long: the printed report's sections in order (compare, evidence, search, verdict), plain printing.
pub fn print_diagnosis(d: &Diagnosis) {
    println!("1. compare (held out: {})", d.held_out);
    println!(
        "   design: path {:.4} m, Eq. 6 {:.4} (train) | path {:.4} m, Eq. 6 {:.4} (held out)",
        d.design_costs.train_path,
        d.design_costs.train_end_pose,
        d.design_costs.held_out_path,
        d.design_costs.held_out_end_pose
    );
    println!(
        "   model:  path {:.4} m, Eq. 6 {:.4} (train) | path {:.4} m, Eq. 6 {:.4} (held out)",
        d.costs.train_path, d.costs.train_end_pose, d.costs.held_out_path, d.costs.held_out_end_pose
    );
    println!("2. where it fails");
    // Directions no run can excite (the wheels fighting each other), held at the design: one line, as there
    // is nothing to do about them; every other finding as it is.
    let nowhere = |f: &Finding| matches!(f, Finding::Unconstrained(w) if w.remedy == Advice::HeldAtDesign);
    let facts = d.facts.len() == d.findings.len();
    let shown = d.findings.iter().enumerate().filter(|(i, _)| !(facts && nowhere(&d.facts[*i])));
    for (_, f) in shown {
        println!("   - {f}");
    }
    let held = if facts { d.facts.iter().filter(|f| nowhere(f)).count() } else { 0 };
    if held > 0 {
        println!(
            "   - the model itself: {} that no run can excite (the wheels fighting each other, which moves the robot \
             nowhere), held at the design: nothing to do",
            crate::units::count(held, "direction")
        );
    }
    if let Some(nf) = &d.noise_floor {
        println!(
            "   noise floor: {:.4} m position, {} heading {} → path RMS ≈ {:.4} m ({} poses)",
            nf.position_m,
            value_text(nf.heading_rad, "rad").trim_start(),
            text::noise_source(nf.source),
            nf.path_rms,
            nf.samples
        );
    }
    if let Some(id) = &d.identifiability {
        let worst = id
            .params
            .iter()
            .filter_map(|p| p.std_error.map(|s| (p.name.as_str(), s / p.scale)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        println!(
            "   identifiability: condition number {:.3e} (scaled){}{}",
            id.condition_number,
            worst.map_or(String::new(), |(n, s)| format!(", largest standard error {n} ({:.3} % of scale)", 100.0 * s)),
            if id.weak.is_empty() { String::new() } else { format!(", {} unconstrained direction(s)", id.weak.len()) }
        );
    }
    println!(
        "3. which effect is missing (held-out gain of the refit `train --effect` makes; first-order share of the residual)"
    );
    println!("   {:<20} {:>9} {:>11} {:>9}  parameters", "effect", "gain %", "1st-order %", "separable");
    for c in &d.ranking {
        let params: Vec<String> = if c.absorbed {
            c.implied.iter().map(|p| format!("{}={}", p.name, param_text(p.value, None, &p.unit))).collect()
        } else {
            c.params
                .iter()
                .map(|p| match p.std_error {
                    Some(se) => format!("{}={}", p.name, param_text(p.value, Some(se), &p.unit)),
                    // Held at its null value by the truncated update, as `train --effect` holds it.
                    None if c.held.contains(&p.name) => {
                        format!(
                            "{}={} (held: the runs do not constrain it; train holds it too)",
                            p.name,
                            param_text(p.value, None, &p.unit)
                        )
                    }
                    // Part of a direction the runs do not constrain (see the identifiability analysis).
                    None => format!("{}={} (undetermined)", p.name, param_text(p.value, None, &p.unit)),
                })
                .collect()
        };
        if let Some(why) = &c.not_excited {
            println!(
                "   {:<20} {:>9} {:>11} {:>9}  not excited: {why}",
                c.effect,
                "-",
                text::percent_1(c.first_order_explained),
                "-"
            );
            continue;
        }
        println!(
            "   {:<20} {:>9} {:>11} {:>9}  {}{}",
            c.effect,
            text::percent_1(c.held_out_gain),
            text::percent_1(c.first_order_explained),
            if c.absorbed { "absorbed".to_string() } else { format!("{:.2}", c.separability) },
            if c.absorbed { "its value undetermined (the model absorbs it)" } else { "" },
            if c.absorbed { String::new() } else { params.join(", ") }
        );
    }
    if let Some(k) = &d.held_out_kinds {
        let folds: Vec<String> = k
            .folds
            .iter()
            .map(|(kind, b, a)| format!("{kind} {b:.4} → {a:.4} m ({:+.1} %)", 100.0 * (a - b) / b.max(1e-300)))
            .collect();
        println!("   {} on the held-out runs by kind of path: {}", k.effect, folds.join(", "));
    }
    if let Some(k) = &d.kind_out {
        let folds: Vec<String> = k.folds.iter().map(|(kind, b, a)| format!("{kind} {b:.4} → {a:.4} m")).collect();
        println!(
            "   {} on kinds of path left out of its fit: {} (path cost {:+.1} %)",
            k.effect,
            folds.join(", "),
            -100.0 * k.gain
        );
    }
    if d.ladder.len() > 2 {
        println!("4. error ladder (path RMS m / Eq. 6)");
        for r in &d.ladder {
            println!(
                "   {:<24} train {:.4} / {:.4}   held out {:.4} / {:.4}",
                r.label, r.costs.train_path, r.costs.train_end_pose, r.costs.held_out_path, r.costs.held_out_end_pose
            );
        }
    }
    println!("verdict: {}", d.verdict_text);
}

/// A ranking parameter's value (and standard error) in its unit: an angle (unit `rad`) as `omnical train`
/// prints it, in degrees with radians in parentheses (`2.0053° (0.034999 rad) ±1.15e-2° (2.00e-4 rad)`);
/// anything else as `0.0602±0.0004 s`.
fn param_text(value: f64, std_error: Option<f64>, unit: &str) -> String {
    match (unit, std_error) {
        ("rad", Some(se)) => format!("{} {}", value_text(value, unit).trim_start(), std_error_text(se, unit)),
        ("rad", None) => value_text(value, unit).trim_start().to_string(),
        (_, Some(se)) => format!("{value:.4}±{se:.4} {unit}"),
        (_, None) => format!("{value:.4} {unit}"),
    }
}

#[cfg(test)]
mod tests {
    use super::param_text;

    #[test]
    fn ranking_angles_print_in_degrees_with_radians() {
        assert_eq!(param_text(0.034999, Some(2.0e-4), "rad"), "2.0053° (0.034999 rad) ±1.15e-2° (2.00e-4 rad)");
        assert_eq!(param_text(-0.001, None, "rad"), "-0.0573° (-0.001000 rad)");
        assert_eq!(param_text(0.0602, Some(0.0004), "s"), "0.0602±0.0004 s");
        assert_eq!(param_text(0.0123, None, "m"), "0.0123 m");
    }
}
