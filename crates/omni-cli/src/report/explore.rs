//! The report's explorer section (`report --explore`): the families by held-out gain with their hints, and
//! for the best family the residual against its strongest term (binned means, the fitted line), as an
//! inline SVG written by hand (a scatter of a few bins and one line).

use omni_ga::explore::{Exploration, FeatureCurve};
use omni_ga::science::text;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The section's HTML: an `<h2 id="explore">`, the ranking table, the conclusion and the curve.
pub fn section(e: &Exploration) -> String {
    let mut h = String::from(
        "<h2 id=\"explore\">Beyond the catalogue (explore)</h2>\n<p class=\"note\">Each family of features \
         refitted with everything else on the training runs, as <code>train --effect learned:&lt;family&gt;</code> fits it \
         (terms the runs do not constrain held at 0, as train holds them); held-out gain = 1 − held-out path cost with it / \
         without it; passes at ≥ 5 % and > 2 standard errors.</p>\n<table><tr><th class=\"l\">family</th>\
         <th class=\"l\">status</th><th>held-out gain %</th><th>± s.e. %</th><th>passes</th>\
         <th class=\"l\">what it says</th></tr>\n",
    );
    for f in &e.families {
        h.push_str(&format!(
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{:+.1}</td><td>{:.1}</td><td>{}</td><td class=\"l\">{}</td></tr>\n",
            f.family.id(),
            esc(&text::family_status(f)),
            100.0 * f.held_out_gain,
            100.0 * f.gain_std_error,
            if f.passes { "yes" } else { "no" },
            esc(&text::explore_hint(f))
        ));
    }
    h.push_str("</table>\n");
    if e.coverage.lacking() {
        h.push_str(&format!("<p>{}</p>\n", esc(&text::motion_coverage(&e.coverage))));
    }
    h.push_str(&format!("<p>{}</p>\n", esc(&text::explore_conclusion(e))));
    if let Some(c) = e.best().and_then(|f| f.curve.as_ref()) {
        h.push_str(&curve_svg(c));
    }
    h
}

/// Binned residual against the feature, with the line `residual = slope · feature`.
fn curve_svg(c: &FeatureCurve) -> String {
    let (w, ht, m) = (560.0, 300.0, 50.0);
    let xs: Vec<f64> = c.bins.iter().map(|b| b.feature).collect();
    let ys: Vec<f64> = c.bins.iter().map(|b| b.residual_m).chain(xs.iter().map(|x| c.slope * x)).collect();
    let (x0, x1) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    let (y0, y1) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| (a.min(y), b.max(y)));
    if !(x1 > x0 && y1 > y0) {
        return String::new();
    }
    let px = |x: f64| m + (x - x0) / (x1 - x0) * (w - 2.0 * m);
    let py = |y: f64| ht - m - (y - y0) / (y1 - y0) * (ht - 2.0 * m);
    let mut s = format!(
        "<figure><svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{ht}\" viewBox=\"0 0 {w} {ht}\">\
         <rect width=\"{w}\" height=\"{ht}\" fill=\"white\"/>\
         <line x1=\"{m}\" y1=\"{b}\" x2=\"{r}\" y2=\"{b}\" stroke=\"black\"/><line x1=\"{m}\" y1=\"{m}\" x2=\"{m}\" y2=\"{b}\" stroke=\"black\"/>\
         <line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#d62728\" stroke-width=\"2\"/>",
        px(x0),
        py(c.slope * x0),
        px(x1),
        py(c.slope * x1),
        b = ht - m,
        r = w - m,
    );
    for b in &c.bins {
        s.push_str(&format!(
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"#1f77b4\"/>",
            px(b.feature),
            py(b.residual_m)
        ));
    }
    s.push_str(&format!(
        "<text x=\"{:.0}\" y=\"{:.0}\" font-size=\"12\" text-anchor=\"middle\">feature of {} (m per {}): {:.3e} … {:.3e}</text>\
         <text x=\"12\" y=\"{:.0}\" font-size=\"12\" transform=\"rotate(-90 12 {:.0})\" text-anchor=\"middle\">residual without the term (m): {:.2e} … {:.2e}</text>\
         </svg><figcaption>Training residual against {} (binned means, equal counts) and the fitted line, slope {:+.4e} {}.</figcaption></figure>\n",
        w / 2.0,
        ht - 12.0,
        esc(&c.term),
        esc(&c.unit),
        x0,
        x1,
        ht / 2.0,
        ht / 2.0,
        y0,
        y1,
        esc(&c.term),
        c.slope,
        esc(&c.unit),
    ));
    s
}
