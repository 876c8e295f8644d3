//! The same bits whatever the route: increments kept or redone, every SIMD path, a run alone or in a lane
//! group of longer and shorter runs.

use super::*;

/// Every error's bits, in run order.
fn bits(e: &FastErrors) -> Vec<u64> {
    (e.at_queries.iter().chain(&e.ends)).flat_map(|e| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits)).collect()
}

#[test]
fn redone_increments_give_the_same_bits_as_kept_ones() {
    let runs: Vec<Run> = paper_size().into_iter().take(23).collect();
    for (effect, values) in [(None, vec![]), (Some("speed_scale"), vec![0.01, -0.02, 0.015])] {
        let (model, p) = paper_with(effect.as_slice(), &values, Integration::DEFAULT);
        let res = model.resolve(&p).unwrap();
        for sel in [Selection::End, Selection::Path(1)] {
            let kept = PreparedRuns::new(&runs, None, sel);
            let redone = PreparedRuns::with_increment_budget(&runs, None, sel, 0);
            assert!(kept.increments_kept() && !redone.increments_kept());
            assert_eq!(bits(&kept.errors(&res, &runs).unwrap()), bits(&redone.errors(&res, &runs).unwrap()));
            let ends = |p: &PreparedRuns| p.end_pose_errors(&res, &runs).unwrap();
            assert_eq!(ends(&kept), ends(&redone));
            if effect.is_none() {
                let rows = |p: &PreparedRuns| {
                    let mut out = Vec::new();
                    (p.ik_jacobian_rows(&res, &runs, &mut |r| {
                        out.push((r.run, r.errors.to_vec(), r.jacobian.clone()))
                    }))
                    .unwrap();
                    out
                };
                assert_eq!(rows(&kept), rows(&redone));
            }
        }
    }
}

/// Runs of 3 wheels and 19 lengths (700 to 3,166 samples: some end before a re-anchoring of the heading
/// that a longer run of their group reaches), so the groups mix lengths.
fn mixed_length_runs() -> Vec<Run> {
    (0..19).map(|seed| synthetic_run_of(3, seed, 700 + 137 * seed)).collect()
}

/// Every lane-arithmetic path this CPU has (portable, AVX2, AVX-512) gives the same bits, at the queries
/// and the ends, for Euler and exact arcs, with a measurement-stage and an affine wheel-stage effect; and
/// those numbers are the literal walk's within 1e-9 m.
#[test]
fn every_simd_path_gives_the_same_bits() {
    let runs = mixed_length_runs();
    assert!(runs.iter().any(|r| r.n_samples() < RESYNC_STEPS) && runs.iter().any(|r| r.n_samples() > 3 * RESYNC_STEPS));
    let paths = SimdPath::available();
    assert_eq!(paths[0], SimdPath::Portable);
    assert_eq!(SimdPath::selected(), *paths.last().unwrap());
    eprintln!("paths compared: {paths:?}");
    for integration in [Integration::PAPER, Integration::DEFAULT] {
        let model = Model::ik(spread_ik(3))
            .with_integration(integration)
            .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap())
            .with_effect(EffectKind::from_id("wheel_asymmetry", 3).unwrap());
        let mut p = spread_ik(3).entries().to_vec();
        p.extend([0.02, -0.01, 0.03, -0.02, 0.01]);
        let res = model.resolve(&p).unwrap();
        for selection in [Selection::End, Selection::Path(1)] {
            let (gap, _) = max_gap(&model, &p, &runs, selection);
            assert!(gap < 1e-9, "{integration:?} {selection:?}: gap {gap:e} m");
            let prepared = PreparedRuns::new(&runs, res.fixed_dt_s, selection);
            let portable = prepared.errors_on(SimdPath::Portable, &res, &runs).unwrap();
            assert_eq!(portable.ends.len(), runs.len());
            for &path in &paths {
                let errors = prepared.errors_on(path, &res, &runs).unwrap();
                assert_eq!(bits(&errors), bits(&portable), "{path:?} {integration:?} {selection:?}");
            }
        }
    }
}

/// A run's errors and IK Jacobian rows are the same bits whether it shares a lane group with longer and
/// shorter runs or walks alone (the heading is not re-anchored past a lane's last step), with a sensor
/// offset (which reads the carried cosine and sine at the end).
#[test]
fn a_runs_numbers_do_not_depend_on_the_runs_in_its_group() {
    let runs = mixed_length_runs();
    // A sensor offset: the end pose reads the heading's cosine and sine.
    let model = Model::ik(spread_ik(3))
        .with_integration(Integration::DEFAULT)
        .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap());
    let mut p = spread_ik(3).entries().to_vec();
    p.extend([0.05, -0.03]);
    let res = model.resolve(&p).unwrap();
    let pose_bits = |e: &PoseError| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits);
    let rows = |p: &PreparedRuns, runs: &[Run]| {
        let mut out = Vec::new();
        p.ik_jacobian_rows(&res, runs, &mut |r| out.push((r.errors.to_vec(), r.jacobian.clone()))).unwrap();
        out
    };
    for selection in [Selection::End, Selection::Path(1)] {
        let prepared = PreparedRuns::new(&runs, None, selection);
        let (all, all_rows) = (prepared.errors(&res, &runs).unwrap(), rows(&prepared, &runs));
        let mut first_query = 0;
        for (i, run) in runs.iter().enumerate() {
            let one = std::slice::from_ref(run);
            let alone_prepared = PreparedRuns::new(one, None, selection);
            let alone = alone_prepared.errors(&res, one).unwrap();
            assert_eq!(pose_bits(&alone.ends[0]), pose_bits(&all.ends[i]), "run {i} {selection:?}");
            let queries = &all.at_queries[first_query..first_query + alone.at_queries.len()];
            assert!(queries.iter().zip(&alone.at_queries).all(|(a, b)| pose_bits(a) == pose_bits(b)), "run {i}");
            first_query += alone.at_queries.len();
            assert_eq!(rows(&alone_prepared, one)[0], all_rows[i], "run {i} {selection:?}");
        }
        assert_eq!(first_query, all.at_queries.len());
    }
}

/// The same on the twist-stage walk (a built-in twist-stage effect and a sensor offset): a run's end-pose
/// error is the same bits alone and in a group of longer and shorter runs.
#[test]
fn a_runs_numbers_on_the_twist_walk_do_not_depend_on_its_group() {
    let runs = mixed_length_runs();
    let model = Model::ik(spread_ik(3))
        .with_integration(Integration::DEFAULT)
        .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap())
        .with_effect(EffectKind::from_id("world_drift", 3).unwrap());
    let mut p = spread_ik(3).entries().to_vec();
    p.extend([0.05, -0.03, 0.004, -0.003]);
    let res = model.resolve(&p).unwrap();
    assert!(!res.twist_effects.is_empty());
    let pose_bits = |e: &PoseError| [e.dx_m, e.dy_m, e.dtheta_rad].map(f64::to_bits);
    let all = PreparedRuns::new(&runs, None, Selection::End).end_pose_errors(&res, &runs).unwrap();
    for (i, run) in runs.iter().enumerate() {
        let one = std::slice::from_ref(run);
        let alone = PreparedRuns::new(one, None, Selection::End).end_pose_errors(&res, one).unwrap();
        assert_eq!(pose_bits(&alone[0]), pose_bits(&all[i]), "run {i}");
    }
}
