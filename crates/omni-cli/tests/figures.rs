//! The README's and docs' figures stay true (issue 48 item 4): each figure below names its place in a
//! document (the text just before the number), the commands and data it comes from, and a tolerance; the
//! test reruns the commands and fails when the printed number drifts beyond the tolerance.
//!
//! - `fast` figures run with every `cargo test` (seconds: small simulated sets, `eval` on the real logs);
//! - `slow` figures (a `train` on the real logs, the 180 + 180-run simulated set) are ignored by default and
//!   run by `scripts/figures.sh` (`--include-ignored`, release build);
//! - timings are not checked here (they depend on the machine and its load): the document says where they
//!   were measured (benches/README.md).
//!
//! `OMNICAL_FIGURES=write` (what `scripts/figures.sh --write` sets) rewrites each figure's number in its
//! document with the regenerated value, in the document's own format (decimals, sign), instead of failing.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use serde_json::Value;
use std::path::{Path, PathBuf};
use support::{json, ok, shared_set};

/// A figure's place: a document of the repository and the text just before the number (unique in it).
struct Place {
    doc: &'static str,
    before: &'static str,
}

/// One figure: where it is printed, how to regenerate it (the commands, in a fresh folder), and how far
/// the regenerated value may be from the printed one (in the printed unit).
struct Figure {
    /// What it is, for messages.
    name: &'static str,
    places: &'static [Place],
    /// The commands and data, run in the folder given; the value in the printed unit.
    measure: fn(&Path) -> f64,
    tolerance: f64,
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The number printed right after `before` in `text`: (its byte range, its value). Accepts a sign (`+`,
/// `-`, `−`), digits, one decimal point; a trailing point ends it.
fn number_after(text: &str, before: &str) -> Option<(std::ops::Range<usize>, f64)> {
    let at = text.find(before)? + before.len();
    let rest = &text[at..];
    let mut end = 0;
    for (i, c) in rest.char_indices() {
        let sign = i == 0 && matches!(c, '+' | '-' | '−');
        if c.is_ascii_digit() || sign || (c == '.' && rest[i + 1..].starts_with(|d: char| d.is_ascii_digit())) {
            end = i + c.len_utf8();
        } else {
            break;
        }
    }
    let value: f64 = rest[..end].replace('−', "-").parse().ok()?;
    Some((at..at + end, value))
}

/// `value` in the format of `printed` (its decimals and explicit sign).
fn formatted_like(printed: &str, value: f64) -> String {
    let decimals = printed.split_once('.').map_or(0, |(_, d)| d.len());
    let sign = if printed.starts_with('+') && value >= 0.0 { "+" } else { "" };
    format!("{sign}{value:.decimals$}")
}

/// The `--json` document of `omnical ARGS` in `dir` (quiet).
fn doc(args: &[&str], dir: &Path) -> Value {
    json(&[&["-q"], args, &["--json"]].concat(), dir)
}

fn f(v: &Value, pointer: &str) -> f64 {
    v.pointer(pointer).and_then(Value::as_f64).unwrap_or_else(|| panic!("no {pointer} in {v}"))
}

/// The controller's loss against the calibrated matrix on a simulated APR-02 (Eq. 9 and `extra`'s
/// `simulate` options): train on train/, `export --robot-config` on validation/. Percent of Eq. 6 and of
/// path RMS.
fn controller_loss_simulated(dir: &Path, extra: &[&str]) -> (f64, f64) {
    ok(&[&["-q", "simulate", "--out", "sim"], extra].concat(), dir);
    ok(&["-q", "train", "sim/train", "--out", "fit.toml"], dir);
    let e = doc(&["export", "--model", "fit.toml", "sim/validation", "--robot-config", "robot"], dir);
    let loss = |what: &str| {
        100.0
            * (f(&e, &format!("/robot_config/accuracy/controller/{what}"))
                / f(&e, &format!("/robot_config/accuracy/model/{what}"))
                - 1.0)
    };
    (loss("end_pose"), loss("path_rms_m"))
}

/// [`controller_loss_simulated`] on the small set (36 + 36 runs of 4 s), made once for the figures that
/// read it.
fn controller_loss_small() -> (f64, f64) {
    static LOSS: std::sync::OnceLock<(f64, f64)> = std::sync::OnceLock::new();
    *LOSS.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        controller_loss_simulated(
            tmp.path(),
            &["--runs-per-command", "1", "--duration", "4", "--effect", "time_offset=0.04"],
        )
    })
}

/// `eval --model MODEL SET --json` on a real OptiOdom set.
fn eval_real(dir: &Path, model: &str, robot: &str, set: &str) -> Value {
    doc(&["eval", "--model", model, &shared_set(robot, set)], dir)
}

/// `train` on one real set, written as fit.toml in `dir`.
fn train_real(dir: &Path, robot: &str, set: &str) {
    ok(&["-q", "train", &shared_set(robot, set), "--out", "fit.toml"], dir);
}

const APPLYING_ROW: &str = "simulated APR-02 flower (Eq. 9 + 40 ms clock lag, 36 runs of 4 s), `omni_wheel_drive_controller` | 0.0856 / 0.0526 | 0.0159 / 0.0101 | 0.0179 / 0.0118 | ";

/// The figures run with every `cargo test`.
const FAST: &[Figure] = &[
    Figure {
        name: "omni_wheel_drive_controller's Eq. 6 loss on the simulated APR-02 (36 runs of 4 s)",
        places: &[
            Place { doc: "README.md", before: "`omni_wheel_drive_controller` (one radius, one distance) gives up " },
            Place { doc: "docs/applying.md", before: "  given up by the controller            " },
            Place { doc: "docs/applying.md", before: APPLYING_ROW },
        ],
        measure: |_| controller_loss_small().0,
        tolerance: 0.05,
    },
    Figure {
        name: "omni_wheel_drive_controller's path RMS loss on the simulated APR-02 (36 runs of 4 s)",
        places: &[
            Place { doc: "docs/applying.md", before: "  given up by the controller            +12.6 %    " },
            Place { doc: "docs/applying.md", before: "| 0.0179 / 0.0118 | +12.6 % / " },
        ],
        measure: |_| controller_loss_small().1,
        tolerance: 0.05,
    },
];

/// The figures on the real logs that need only `eval` (run with every `cargo test` when the logs are here).
const REAL_FAST: &[Figure] = &[
    Figure {
        name: "omni3 design, Eq. 6 on the held-out set 221220201953",
        places: &[Place { doc: "README.md", before: "| omni3 | `221220201934` | " }],
        measure: |d| f(&eval_real(d, "design", "omni3", "221220201953"), "/cost"),
        tolerance: 0.00005,
    },
    Figure {
        name: "omni3 design, path RMS on the held-out set 221220201953",
        places: &[Place { doc: "README.md", before: "| omni3 | `221220201934` | 0.1922 / " }],
        measure: |d| f(&eval_real(d, "design", "omni3", "221220201953"), "/path_cost"),
        tolerance: 0.00005,
    },
    Figure {
        name: "omni4 design, Eq. 6 on the held-out set 231220200521",
        places: &[Place { doc: "README.md", before: "| omni4 | `080920201715` | " }],
        measure: |d| f(&eval_real(d, "design", "omni4", "231220200521"), "/cost"),
        tolerance: 0.00005,
    },
    Figure {
        name: "omni4 design, Eq. 6 on the held-out set 080920201715",
        places: &[Place { doc: "README.md", before: "| omni4 | `231220200521` | " }],
        measure: |d| f(&eval_real(d, "design", "omni4", "080920201715"), "/cost"),
        tolerance: 0.00005,
    },
    Figure {
        name: "omni3 design, drift per 1 m on the held-out set 221220201953",
        places: &[Place { doc: "README.md", before: "omni3's held-out set `221220201953` drifts " }],
        measure: |d| f(&eval_real(d, "design", "omni3", "221220201953"), "/rpe/drift_pct/mean"),
        tolerance: 0.05,
    },
];

/// The figures `scripts/figures.sh` regenerates (a `train` on the real logs; the default simulated set).
const SLOW: &[Figure] = &[
    Figure {
        name: "omni3 ik fitted on 221220201934, Eq. 6 on the held-out set 221220201953",
        places: &[Place { doc: "README.md", before: "| omni3 | `221220201934` | 0.1922 / 0.1499 | **" }],
        measure: |d| {
            train_real(d, "omni3", "221220201934");
            f(&eval_real(d, "fit.toml", "omni3", "221220201953"), "/cost")
        },
        tolerance: 0.0005,
    },
    Figure {
        name: "omni4 ik fitted on 080920201715, Eq. 6 on the held-out set 231220200521",
        places: &[Place { doc: "README.md", before: "| omni4 | `080920201715` | 0.9840 / 0.4675 | **" }],
        measure: |d| {
            train_real(d, "omni4", "080920201715");
            f(&eval_real(d, "fit.toml", "omni4", "231220200521"), "/cost")
        },
        tolerance: 0.0005,
    },
    Figure {
        name: "the default simulated set's design cost (Eq. 6, train split)",
        places: &[Place { doc: "README.md", before: "| design (Eq. 7) | " }],
        measure: |d| f(&doc(&["simulate", "--out", "sim"], d), "/splits/train/design_end_pose"),
        tolerance: 0.00005,
    },
    Figure {
        name: "omni_wheel_drive_controller's Eq. 6 loss on the default simulated set (180 + 180 runs of 10 s)",
        places: &[Place { doc: "README.md", before: "clock lag) it gives up " }],
        measure: |d| controller_loss_simulated(d, &[]).0,
        tolerance: 1.0,
    },
];

/// Checks (or, with `OMNICAL_FIGURES=write`, rewrites) every place of every figure.
fn check(figures: &[Figure]) {
    let write = std::env::var("OMNICAL_FIGURES").is_ok_and(|v| v == "write");
    let mut drifted = Vec::new();
    for fig in figures {
        let tmp = tempfile::tempdir().unwrap();
        let value = (fig.measure)(tmp.path());
        for place in fig.places {
            let path = root().join(place.doc);
            let text = std::fs::read_to_string(&path).unwrap();
            let (range, printed) = number_after(&text, place.before)
                .unwrap_or_else(|| panic!("{}: no number after {:?} ({})", place.doc, place.before, fig.name));
            if (printed - value).abs() <= fig.tolerance {
                continue;
            }
            if write {
                let new = formatted_like(&text[range.clone()], value);
                std::fs::write(&path, format!("{}{new}{}", &text[..range.start], &text[range.end..])).unwrap();
            } else {
                drifted.push(format!(
                    "{}: {} prints {printed}, now {value} (tolerance {})",
                    place.doc, fig.name, fig.tolerance
                ));
            }
        }
    }
    assert!(
        drifted.is_empty(),
        "figures drifted (scripts/figures.sh --write regenerates them):\n{}",
        drifted.join("\n")
    );
}

/// Every figure's place is in its document, once, with a number after it.
#[test]
fn every_figure_has_its_place() {
    for fig in FAST.iter().chain(REAL_FAST).chain(SLOW) {
        for place in fig.places {
            let text = std::fs::read_to_string(root().join(place.doc)).unwrap();
            assert_eq!(text.matches(place.before).count(), 1, "{}: {:?} ({})", place.doc, place.before, fig.name);
            assert!(number_after(&text, place.before).is_some(), "{}: {:?}", place.doc, place.before);
        }
    }
}

#[test]
fn simulated_figures_hold() {
    check(FAST);
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs the real robot logs ../shared/data (see crates/omni-cli/build.rs)")]
fn real_robot_figures_hold() {
    check(REAL_FAST);
}

#[test]
#[ignore = "slow (a train on the real logs, the 180 + 180-run simulated set): scripts/figures.sh runs it"]
fn slow_figures_hold() {
    check(SLOW);
}

#[test]
fn numbers_are_read_and_written_in_their_format() {
    let text = "gives up +12.6 % Eq. 6; drifts 5.3 % of; | 0.1922 / 0.1499 |; −81 %";
    assert_eq!(number_after(text, "gives up ").map(|(_, v)| v), Some(12.6));
    assert_eq!(number_after(text, "drifts ").map(|(_, v)| v), Some(5.3));
    assert_eq!(number_after(text, "| 0.1922 / ").map(|(_, v)| v), Some(0.1499));
    assert_eq!(number_after(text, "; ").map(|(_, v)| v), None);
    assert_eq!(formatted_like("+12.6", 241.04), "+241.0");
    assert_eq!(formatted_like("0.1922", 0.19217822), "0.1922");
}
