//! Unit tests of the report: its content against the models, figures and page without a diagnosis, legends, thinning.

#![allow(clippy::unwrap_used)]
use super::*;
use omni_kin::simulate::{SimConfig, flower_commands, simulate};
use omni_kin::{IkMatrix, Model};

fn runs() -> Vec<Run> {
    let config = SimConfig {
        commands: flower_commands().into_iter().step_by(4).collect(),
        runs_per_command: 1,
        duration_s: 3.0,
        ..SimConfig::default()
    };
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    simulate(&config, &truth, "r/").unwrap()
}

fn input(runs: &[Run]) -> ReportInput<'_> {
    ReportInput {
        title: "t <&>".into(),
        models: vec![
            Labelled { label: "design".into(), model: FittedModel::paper_design().into(), noise: None },
            Labelled {
                label: "truth".into(),
                model: FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated())).into(),
                noise: None,
            },
        ],
        train: runs,
        held_out: &[],
        diagnosis: None,
        sources: vec![],
    }
}

#[test]
fn report_content_matches_the_models() {
    let runs = runs();
    let r = Report::build(&input(&runs)).unwrap();
    assert_eq!(r.runs.len(), runs.len());
    assert_eq!(r.figure_runs, "training runs (no validation set given)");
    // The true matrix beats the design on every run.
    for x in &r.runs {
        assert!(x.end_position_m[1] < x.end_position_m[0], "{}: {:?}", x.name, x.end_position_m);
    }
    let mean = |m: usize| r.runs.iter().map(|x| x.path_rms_m[m]).sum::<f64>() / r.runs.len() as f64;
    assert!(mean(1) < 0.6 * mean(0), "path RMS truth {} vs design {}", mean(1), mean(0));
    // Costs are the library's.
    let eq6 = omni_kin::cost::cost(
        &FittedModel::paper_design().model,
        &FittedModel::paper_design().params,
        &runs,
        CostKind::EndPose,
    )
    .unwrap();
    assert_eq!(r.models[0].costs.held_out_end_pose, eq6);
    assert_eq!(r.ladder.len(), 2);
    // The worst overlay is the run with the largest path RMS of the second model.
    let worst = r.runs.iter().max_by(|a, b| a.path_rms_m[1].total_cmp(&b.path_rms_m[1])).unwrap();
    assert_eq!(r.overlays[0].run, worst.name);
    assert_eq!(r.overlays[0].lines.len(), 3);
    // Design error grows along the runs; growth has one curve per model.
    assert_eq!(r.growth.position_m.len(), 2);
    let g = &r.growth.position_m[0];
    assert!(g[GROWTH_BINS - 1] > 3.0 * g[1], "{g:?}");
}

#[test]
fn figures_and_page_without_a_diagnosis() {
    let runs = runs();
    let r = Report::build(&input(&runs)).unwrap();
    let (figs, notes) = figures::all(&r, None).unwrap();
    let ids: Vec<&str> = figs.iter().map(|f| f.id.as_str()).collect();
    assert_eq!(ids, ["ladder", "overlay-worst", "overlay-typical", "flower", "heat-map", "growth"]);
    assert_eq!(
        notes,
        [
            "The model has no odometry noise model (a model file written by `omnical train` carries one as \
             [noise]), so the figures of how far to trust the odometry are left out.",
            "No diagnosis was run, so the effect ranking is left out."
        ]
    );
    assert!(figs.iter().all(|f| f.svg.contains("<svg") && f.svg.len() > 2000));
    let page = html::render(&r, &figs, &notes, None);
    assert!(page.contains("<title>t &lt;&amp;&gt;</title>"));
    assert_eq!(page.matches("<svg").count(), 6);
    assert!(!page.contains("<?xml"));
}

#[test]
fn flower_and_overlays_have_legends() {
    let runs = runs();
    let r = Report::build(&input(&runs)).unwrap();
    let (figs, _) = figures::all(&r, None).unwrap();
    let svg = |id: &str| figs.iter().find(|f| f.id == id).map(|f| f.svg.clone()).unwrap();
    // plotters writes each text element's content on a line of its own.
    let text = |s: &str| format!(">\n{s}\n</text>");
    // The flower leaves the design out (its errors are on another scale) and names the model it draws,
    // in its colour (blue: the second model).
    let flower = svg("flower");
    assert!(flower.contains(&text("mean end position error of:")), "{flower}");
    assert!(flower.contains(&text("truth")), "{flower}");
    assert!(!flower.contains(&text("design")), "{flower}");
    assert!(flower.contains(r##"stroke="#1F77B4""##), "{flower}");
    // Each overlay names ground truth and every model's odometry.
    for id in ["overlay-worst", "overlay-typical"] {
        let o = svg(id);
        for label in ["ground truth", "design", "truth"] {
            assert!(o.contains(&text(label)), "{id}: no legend entry {label}");
        }
    }
}

#[test]
fn thinning_keeps_the_last_pose() {
    let poses: Vec<Pose2> = (0..1001).map(|k| Pose2 { x_m: k as f64, y_m: 0.0, theta_rad: 0.0 }).collect();
    let t = thin(&poses);
    assert!(t.len() <= 602);
    assert_eq!(t.first().unwrap().0, 0.0);
    assert_eq!(t.last().unwrap().0, 1000.0);
    assert_eq!(t.iter().filter(|p| p.0 == 1000.0).count(), 1);
}
