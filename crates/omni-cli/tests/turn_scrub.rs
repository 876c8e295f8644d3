//! An effect that needs motion the training lacks (issue 45 item 3): a 4-wheel omni robot whose turn rate
//! falls while it drives (`turn_scrub`, k = −0.26 s/m). On squares alone (sides, then turns on the spot) the
//! runs cannot see it: `train --effect turn_scrub` holds it at 0 and says so. With circles added, the
//! default fit finds it, without `--unexcited move`: before, the base's own unconstrained directions (the
//! wheels fighting each other) made the refit hold every direction found at the effect's null, where its
//! misfit inflated its standard error to 5.8 % of its scale, and k stayed near 0.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use support::{json, omni_toml, param_se, succeeded};

#[test]
fn turn_scrub_is_held_on_squares_and_found_by_default_once_circles_are_added() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // A 4-wheel omni robot, wheels at 45°, 135°, 225° and 315°.
    std::fs::write(d.join("omni4.toml"), omni_toml("omni4", 0.0508, 0.21, &[45.0, 135.0, 225.0, 315.0])).unwrap();
    let squares = "0.2,0,0,2\n0.2,90,0,2\n0.2,180,0,2\n0.2,-90,0,2\n0,0,0.6,2\n0,0,-0.6,2\n";
    let circles = "0.2,0,0.4,2\n0.2,0,-0.4,2\n0.3,90,0.3,2\n0.3,-90,-0.3,2\n";
    let header = "v_m_s,alpha_deg,omega_rad_s,repetitions\n";
    std::fs::write(d.join("squares.csv"), format!("{header}{squares}")).unwrap();
    std::fs::write(d.join("both.csv"), format!("{header}{squares}{circles}")).unwrap();
    for set in ["squares", "both"] {
        let sim = ["simulate", "--robot", "omni4.toml", "--commands", &format!("{set}.csv"), "--out", set];
        succeeded(&[&sim[..], &["--effect", "turn_scrub=-0.26", "--duration", "8", "-q"]].concat(), d);
    }
    let train = |set: &str| json(&["train", &format!("{set}/train"), "--effect", "turn_scrub", "--json"], d);
    let squares = train("squares");
    let (held, _) = param_se(&squares, "turn_scrub.k_s_m");
    assert!(held.abs() < 1e-9, "squares: k {held}");
    let notes = squares["identifiability"]["weak"].to_string();
    assert!(notes.contains("turn_scrub.k_s_m"), "squares: the held direction names it: {notes}");
    let (found, se) = param_se(&train("both"), "turn_scrub.k_s_m");
    eprintln!("squares and circles: k = {found} ± {se} s/m (truth -0.26)");
    assert!((found + 0.26).abs() < 0.013, "k {found}");
    assert!(se < 0.01, "{se}");
}
