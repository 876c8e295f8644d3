//! One self-contained HTML page: inline CSS and SVG, no scripts, no fetches.

use super::Report;
use super::figures::Figure;
use omni_ga::diagnose::Diagnosis;
use std::fmt::Write;

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

const STYLE: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:960px;margin:2em auto;\
padding:0 1em;color:#222;line-height:1.45}h1{font-size:1.6em;margin-bottom:.2em}h2{margin-top:1.8em;\
border-bottom:1px solid #ddd;padding-bottom:.2em}table{border-collapse:collapse;margin:.6em 0}\
td,th{border:1px solid #ddd;padding:.25em .6em;text-align:right;font-variant-numeric:tabular-nums}\
th{background:#f5f5f5}td.l,th.l{text-align:left}figure{margin:1.2em 0}figure svg{max-width:100%;height:auto;\
border:1px solid #eee}figcaption{color:#555;font-size:.93em}.verdict{background:#eef7ee;border-left:4px solid \
#2ca02c;padding:.6em 1em}.note{color:#777;font-size:.9em}code{background:#f3f3f3;padding:0 .25em}";

/// The report page.
pub fn render(r: &Report, figures: &[Figure], notes: &[String], diagnosis: Option<&Diagnosis>) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        escape(&r.title),
        escape(&r.title)
    );
    let _ = writeln!(
        h,
        "<p class=\"note\">omnical {} · {} · figures on {} ({})</p>",
        env!("CARGO_PKG_VERSION"),
        crate::units::count(r.train_runs, "training run"),
        escape(&r.figure_runs),
        crate::units::count(r.runs.len(), "run")
    );
    if let Some(d) = diagnosis {
        let _ = writeln!(h, "<p class=\"verdict\"><b>Verdict.</b> {}</p>", escape(&d.verdict_text));
    }
    summary(&mut h, r);
    if let Some(d) = diagnosis {
        findings(&mut h, d);
    }
    h.push_str("<h2 id=\"figures\">Figures</h2>\n");
    for f in figures {
        let _ = writeln!(
            h,
            "<figure class=\"figure\" id=\"fig-{}\" data-figure=\"{}\"><h3>{}</h3>\n{}\n<figcaption>{}</figcaption>\
             </figure>",
            escape(&f.id),
            escape(&f.id),
            escape(&f.title),
            strip_xml_declaration(&f.svg),
            escape(&f.caption)
        );
    }
    for n in notes {
        let _ = writeln!(h, "<p class=\"note\">{}</p>", escape(n));
    }
    if let Some(d) = diagnosis {
        ranking_table(&mut h, d);
    }
    if !r.sources.is_empty() {
        h.push_str("<h2>Data</h2>\n<ul>\n");
        for s in &r.sources {
            let _ = writeln!(h, "<li><code>{}</code></li>", escape(s));
        }
        h.push_str("</ul>\n");
    }
    h.push_str("</body></html>\n");
    h
}

fn strip_xml_declaration(svg: &str) -> &str {
    match svg.strip_prefix("<?xml") {
        Some(rest) => rest.split_once("?>").map_or(svg, |(_, body)| body.trim_start()),
        None => svg,
    }
}

fn summary(h: &mut String, r: &Report) {
    h.push_str("<h2 id=\"summary\">Summary</h2>\n<table><tr><th class=\"l\">model</th>");
    h.push_str("<th>train path RMS (m)</th><th>train Eq. 6</th><th>held-out path RMS (m)</th><th>held-out Eq. 6</th>");
    h.push_str("<th>vs design (held-out Eq. 6)</th></tr>\n");
    let base = r.models.first().map(|m| m.costs.held_out_end_pose);
    for m in &r.models {
        let change = match base {
            Some(b) if b > 0.0 => format!("{:+.1} %", 100.0 * (m.costs.held_out_end_pose - b) / b),
            _ => "–".into(),
        };
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{:.5}</td><td>{:.5}</td><td>{:.5}</td><td>{:.5}</td><td>{}</td></tr>",
            escape(&m.label),
            m.costs.train_path,
            m.costs.train_end_pose,
            m.costs.held_out_path,
            m.costs.held_out_end_pose,
            change
        );
    }
    h.push_str(
        "</table>\n<p class=\"note\">Path RMS: every ground-truth pose, heading weighted 1 m/rad. Eq. 6: the \
                paper's mean end-pose error (metres and radians added).</p>\n",
    );
    for m in r.models.iter().skip(1) {
        let _ = writeln!(h, "<h3>{}</h3>", escape(&m.label));
        if let Some(rows) = &m.matrix {
            h.push_str("<table><tr><th class=\"l\">IK matrix</th>");
            for j in 0..rows.first().map_or(0, Vec::len) {
                let _ = write!(h, "<th>wheel {}</th>", j + 1);
            }
            h.push_str("</tr>\n");
            for (row, name) in rows.iter().zip(["v<sub>x</sub> (m/s)", "v<sub>y</sub> (m/s)", "ω (rad/s)"]) {
                let _ = write!(h, "<tr><td class=\"l\">{name} per rad/s</td>");
                for v in row {
                    let _ = write!(h, "<td>{v:.6}</td>");
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</table>\n");
        }
        if !m.params.is_empty() {
            h.push_str("<table><tr><th class=\"l\">parameter</th><th>value</th><th class=\"l\">unit</th></tr>\n");
            for (name, v, unit) in &m.params {
                let _ = writeln!(
                    h,
                    "<tr><td class=\"l\">{}</td><td>{v:.6}</td><td class=\"l\">{}</td></tr>",
                    escape(name),
                    escape(unit)
                );
            }
            h.push_str("</table>\n");
        }
    }
}

fn findings(h: &mut String, d: &Diagnosis) {
    h.push_str("<h2 id=\"findings\">Where the model fails</h2>\n<ul>\n");
    for f in &d.findings {
        let _ = writeln!(h, "<li>{}</li>", escape(f));
    }
    if let Some(nf) = &d.noise_floor {
        let _ = writeln!(
            h,
            "<li>Noise floor {}: {:.4} m position, {:.4} rad heading → path RMS ≈ {:.4} m ({} poses).</li>",
            omni_ga::science::text::noise_source(nf.source),
            nf.position_m,
            nf.heading_rad,
            nf.path_rms,
            nf.samples
        );
    }
    h.push_str("</ul>\n");
    identifiability(h, d);
}

/// What the training runs constrain: standard errors, condition number, unconstrained directions.
fn identifiability(h: &mut String, d: &Diagnosis) {
    let Some(id) = &d.identifiability else { return };
    let _ = writeln!(
        h,
        "<h2 id=\"identifiability\">What the runs can calibrate</h2>\n<p class=\"note\">Standard errors of the \
         model's parameters on the training runs ({}), condition number of the scaled Jacobian {:.3e}.</p>\n\
         <table><tr><th class=\"l\">parameter</th><th>value</th><th>standard error</th><th>% of scale</th></tr>",
        match id.covariance_kind {
            omni_ga::identify::CovarianceKind::PerRun => "per-run estimate, robust to errors correlated along a path",
            _ => "assuming independent residuals",
        },
        id.condition_number
    );
    for p in &id.params {
        let (se, pct) = match p.std_error {
            Some(se) => (format!("±{se:.3e} {}", escape(&p.unit)), format!("{:.3}", 100.0 * se / p.scale)),
            None => ("undetermined".to_string(), "–".to_string()),
        };
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{:.6}</td><td>{se}</td><td>{pct}</td></tr>",
            escape(&p.name),
            p.value
        );
    }
    h.push_str("</table>\n");
    if id.weak.is_empty() {
        h.push_str("<p>Every direction of parameter space is constrained by these runs.</p>\n");
    } else {
        h.push_str("<ul>\n");
        for w in id.warnings() {
            let _ = writeln!(h, "<li class=\"warn\">{}</li>", escape(&w));
        }
        h.push_str("</ul>\n");
    }
}

/// A share (0…1) in percent with one decimal and its sign, `-` when not measured (never `NaN` or `-0.0`).
fn pct(share: f64) -> String {
    match omni_ga::science::text::percent_1(share) {
        p if p == "-" => p,
        p => format!("{p} %"),
    }
}

fn ranking_table(h: &mut String, d: &Diagnosis) {
    let _ = writeln!(
        h,
        "<h2 id=\"ranking\">Diagnosis ranking</h2>\n<p class=\"note\">Held out: {}.</p>\n<table><tr>\
         <th class=\"l\">effect</th><th class=\"l\">physics</th><th>held-out gain</th><th>first-order share</th>\
         <th>separability</th><th class=\"l\">parameters</th></tr>",
        escape(&d.held_out)
    );
    for c in &d.ranking {
        let params: Vec<String> = (if c.absorbed { &c.implied } else { &c.params })
            .iter()
            .map(|p| match p.std_error {
                Some(se) => format!("{} = {:.4} ± {:.4} {}", p.name, p.value, se, p.unit),
                // Implied values carry no standard error; a refit's value without one is undetermined.
                None if c.absorbed => format!("{} = {:.4} {}", p.name, p.value, p.unit),
                None => format!("{} = {:.4} {} (undetermined)", p.name, p.value, p.unit),
            })
            .collect();
        if let Some(why) = &c.not_excited {
            let _ = writeln!(
                h,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>-</td><td>{}</td><td>-</td>\
                 <td class=\"l\">not excited: {}</td></tr>",
                escape(&c.effect),
                escape(&c.physics),
                pct(c.first_order_explained),
                escape(why)
            );
            continue;
        }
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td class=\"l\">{}{}</td></tr>",
            escape(&c.effect),
            escape(&c.physics),
            pct(c.held_out_gain),
            pct(c.first_order_explained),
            if c.absorbed { "absorbed".into() } else { format!("{:.2}", c.separability) },
            if c.absorbed { "its value undetermined (the model absorbs it)" } else { "" },
            if c.absorbed { String::new() } else { escape(&params.join(", ")) }
        );
    }
    h.push_str("</table>\n");
}
