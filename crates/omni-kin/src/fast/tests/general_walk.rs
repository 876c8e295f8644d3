//! The general fast walk (one run at a time) against the literal walk, for every effect the lanes do not
//! serve, and what it declines.

use super::*;

/// Largest difference between the general fast walk and the literal walk (every selected pose and end
/// pose), and the number of poses compared; panics when the general walk declines.
fn general_gap(model: &Model, params: &[f64], runs: &[Run], selection: Selection) -> (f64, usize) {
    let res = model.resolve(params).unwrap();
    let general = crate::evaluate::general_errors(&res, runs, selection).expect("the general walk serves");
    let walk = Evaluator::with_route(model, runs, selection, Route::Walk).unwrap().errors(&res);
    let fast = Evaluator::new(model, runs, selection).unwrap();
    let (mut gap, mut count) = (0.0f64, 0);
    let mut at = |a: &PoseError, b: &PoseError| {
        gap = gap.max((a.dx_m - b.dx_m).abs()).max((a.dy_m - b.dy_m).abs()).max((a.dtheta_rad - b.dtheta_rad).abs());
    };
    let (via_evaluator, ends) = (fast.errors(&res), fast.end_pose_errors(&res));
    for (i, end) in ends.iter().enumerate() {
        assert_eq!(general.run(i).len(), walk.run(i).len());
        for ((a, b), c) in general.run(i).iter().zip(walk.run(i)).zip(via_evaluator.run(i)) {
            at(a, b);
            at(c, b);
            count += 1;
        }
        at(&general.ends()[i], &walk.ends()[i]);
        at(end, &walk.ends()[i]);
    }
    (gap, count)
}

/// Every effect the lane kernel does not serve (a clock lag either way, each twist-stage effect, measured
/// stamps), alone and mixed with wheel- and measurement-stage effects: the general fast walk agrees with
/// the literal walk within 1e-9 m, Euler and exact arcs, end and path selections.
#[test]
fn general_walk_agrees_with_the_literal_walk_for_every_effect() {
    let runs = jittered_runs(7);
    let cases: Vec<(Vec<&str>, Vec<f64>)> = vec![
        (vec!["time_offset"], vec![0.037]),
        (vec!["time_offset"], vec![-0.052]),
        (vec!["rotation_slip"], vec![0.12]),
        (vec!["turn_scrub"], vec![-0.13]),
        (vec!["world_drift"], vec![0.004, -0.003]),
        (vec!["sample_timing"], vec![]),
        (vec!["learned:body"], vec![0.05, 0.02, 0.1, -0.05, 0.03, 0.02, -0.01, 0.015, 0.01]),
        (vec!["learned:world"], vec![0.003, -0.002, 0.01, -0.02, 0.015, -0.01]),
        (vec!["learned:time"], vec![0.001, -0.0005, 0.002, 0.003]),
        (
            vec!["time_offset", "rotation_slip", "wheel_eccentricity", "sensor_offset_yaw", "world_drift"],
            vec![0.02, -0.1, 0.02, -0.01, 0.01, 0.015, 0.0, -0.02, 0.03, -0.02, 0.05, 0.002, 0.001],
        ),
        (vec!["sample_timing", "time_offset", "learned:time"], vec![-0.01, 0.001, 0.0, -0.002, 0.001]),
    ];
    for (ids, values) in cases {
        for integration in [Integration::PAPER, Integration::DEFAULT] {
            let (model, p) = paper_with(&ids, &values, integration);
            assert_eq!(p.len(), model.n_params(), "{ids:?}");
            for selection in [Selection::End, Selection::Path(1), Selection::Path(7)] {
                let (gap, count) = general_gap(&model, &p, &runs, selection);
                eprintln!("{ids:?} {:?} {selection:?}: largest gap {gap:.1e} m", integration.scheme);
                assert!(gap < 1e-9, "{ids:?} {integration:?} {selection:?}: gap {gap:e} m");
                assert!(count >= runs.len(), "{count} poses");
            }
        }
    }
}

/// A step angle beyond the polynomials' range: the general walk declines, and the evaluator's numbers
/// are the literal walk's.
#[test]
fn general_walk_declines_large_step_angles() {
    let runs = jittered_runs(3);
    let model = Model::ik(IkMatrix::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 50.0, 50.0, 50.0]).unwrap())
        .with_effect(EffectKind::from_id("rotation_slip", 3).unwrap());
    let p = model.nominal();
    let res = model.resolve(&p).unwrap();
    assert!(crate::evaluate::general_errors(&res, &runs, Selection::Path(1)).is_none());
    let via = Evaluator::new(&model, &runs, Selection::Path(1)).unwrap().errors(&res);
    let walk = Evaluator::with_route(&model, &runs, Selection::Path(1), Route::Walk).unwrap().errors(&res);
    assert_eq!(via, walk);
}
