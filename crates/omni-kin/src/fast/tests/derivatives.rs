//! The Jacobians against central differences: the kernel's IK Jacobian (in run order across batches, six
//! wheels, a clock lag, wheel-stage effects, chained through a parametric model) and the forward walk's.

use super::*;

/// The residuals and IK Jacobian of `kind`, the evaluator's blocks stacked.
fn stacked(ev: &Evaluator<'_>, res: &crate::model::Resolved<'_>, kind: CostKind) -> (Vec<f64>, DMatrix<f64>) {
    let mut blocks: Vec<(Vec<f64>, DMatrix<f64>)> = Vec::new();
    ev.ik_jacobian_blocks(res, kind, &mut |b: IkBlock<'_>| blocks.push((b.residuals.to_vec(), b.jacobian.clone())))
        .unwrap();
    let rows: usize = blocks.iter().map(|b| b.0.len()).sum();
    let mut jac = DMatrix::zeros(rows, blocks.first().map_or(0, |b| b.1.ncols()));
    let mut r = Vec::new();
    for (res, j) in blocks {
        jac.rows_mut(r.len(), res.len()).copy_from(&j);
        r.extend(res);
    }
    (r, jac)
}

/// Column `c` of the Jacobian `j` (rows: the residuals of `kind`) against central differences of the
/// evaluator's residuals in parameter `c` of `x` (step `1e-6 · max(|x_c|, floor)`): the largest gap
/// relative to the column's largest entry (tiny entries carry the differences' rounding noise), and that
/// entry.
fn column_gap(
    ev: &Evaluator<'_>,
    model: &Model,
    x: &[f64],
    j: &DMatrix<f64>,
    c: usize,
    kind: CostKind,
    floor: f64,
) -> (f64, f64) {
    let h = 1e-6 * x[c].abs().max(floor);
    let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
    xp[c] += h;
    xm[c] -= h;
    let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), kind);
    let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), kind);
    let col_max = (0..j.nrows()).map(|i| j[(i, c)].abs()).fold(0.0f64, f64::max);
    let gap = (0..j.nrows()).map(|i| ((rp[i] - rm[i]) / (2.0 * h) - j[(i, c)]).abs()).fold(0.0f64, f64::max);
    (gap / col_max, col_max)
}

#[test]
fn jacobian_blocks_come_in_run_order_across_batches() {
    let runs: Vec<Run> = paper_size().into_iter().cycle().take(BLOCK_RUNS + 2 * LANES + 1).collect();
    let model = Model::ik(IkMatrix::paper_design());
    let ev = Evaluator::new(&model, &runs, Selection::Path(1)).unwrap();
    let x = IkMatrix::paper_calibrated().entries().to_vec();
    let res = model.resolve(&x).unwrap();
    let full = ev.residual_vector(&res, CostKind::PATH);
    let (mut next, mut row) = (0, 0);
    ev.ik_jacobian_blocks(&res, CostKind::PATH, &mut |b| {
        assert_eq!(b.run, next);
        let rows = 3 * (runs[b.run].truth().len() - 1);
        assert_eq!((b.residuals.len(), b.jacobian.nrows(), b.jacobian.ncols()), (rows, rows, 9));
        for (a, f) in b.residuals.iter().zip(&full[row..row + rows]) {
            assert!((a - f).abs() < 1e-15, "run {}: {a} vs {f}", b.run);
        }
        next += 1;
        row += rows;
    })
    .unwrap();
    assert_eq!((next, row), (runs.len(), full.len()));
}

#[test]
fn ik_jacobian_matches_central_differences() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
    for (integration, kind) in [
        (Integration::PAPER, CostKind::EndPose),
        (Integration::DEFAULT, CostKind::EndPose),
        (Integration::DEFAULT, CostKind::PATH),
        (Integration::PAPER, CostKind::Path { every: 3, heading_weight_m_per_rad: 0.5 }),
    ] {
        let model = Model::ik(IkMatrix::paper_design())
            .with_integration(integration)
            .with_effect(EffectKind::from_id("sensor_offset", 3).unwrap());
        let ev = Evaluator::for_cost(&model, &runs, kind).unwrap();
        let mut x = IkMatrix::paper_calibrated().entries().to_vec();
        x.extend([0.02, -0.01]);
        let res = model.resolve(&x).unwrap();
        let (r, j) = stacked(&ev, &res, kind);
        let fast = ev.residual_vector(&res, kind);
        assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "residuals differ");
        assert_eq!(j.ncols(), 9);
        let mut worst = 0.0f64;
        for c in 0..9 {
            let (gap, col_max) = column_gap(&ev, &model, &x, &j, c, kind, 0.05);
            assert!(col_max > 1e-3, "column {c} is flat");
            worst = worst.max(gap);
        }
        assert!(worst < 1e-6, "{integration:?} {kind:?}: worst relative gap {worst:e}");
    }
}

#[test]
fn ik_jacobian_serves_six_wheels() {
    let runs: Vec<Run> = (0..5).map(|s| synthetic_run(6, s)).collect();
    let model = Model::ik(spread_ik(6)).with_integration(Integration::DEFAULT);
    let ev = Evaluator::for_cost(&model, &runs, CostKind::PATH).unwrap();
    let x = model.nominal();
    let (_, j) = stacked(&ev, &model.resolve(&x).unwrap(), CostKind::PATH);
    assert_eq!(j.ncols(), 18);
    for c in [0, 7, 14, 17] {
        let (gap, _) = column_gap(&ev, &model, &x, &j, c, CostKind::PATH, 0.01);
        assert!(gap < 1e-6, "column {c}: relative gap {gap:e}");
    }
}

/// The fast path's IK Jacobian chained through the model's `twist_from_wheels_jacobian` (what the LM
/// polish uses for parametric models) against central differences in the model's own parameters.
#[test]
fn chained_jacobian_of_diff_and_mecanum_models_matches_central_differences() {
    for (model, x) in robot_type_models() {
        let runs: Vec<Run> = (0..4).map(|s| synthetic_run(model.n_wheels(), s)).collect();
        let ev = Evaluator::for_cost(&model, &runs, CostKind::PATH).unwrap();
        let (_, j_ik) = stacked(&ev, &model.resolve(&x).unwrap(), CostKind::PATH);
        let j = j_ik * model.kinematics.twist_from_wheels_jacobian(&x).unwrap();
        assert_eq!(j.ncols(), x.len());
        for c in 0..x.len() {
            let (gap, col_max) = column_gap(&ev, &model, &x, &j, c, CostKind::PATH, 0.0);
            assert!(col_max > 1e-3, "{}: column {c} is flat", model.kinematics.id());
            assert!(gap < 1e-6, "{} column {c}: relative gap {gap:e}", model.kinematics.id());
        }
    }
}

/// With a clock lag the IK Jacobian is still the kernel's forward-mode one (the lag's own column is the
/// caller's finite difference): it matches central differences.
#[test]
fn ik_jacobian_with_a_clock_lag_matches_central_differences() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
    for kind in [CostKind::EndPose, CostKind::PATH] {
        let model = Model::ik(IkMatrix::paper_design()).with_effect(EffectKind::from_id("time_offset", 3).unwrap());
        let ev = Evaluator::for_cost(&model, &runs, kind).unwrap();
        let mut x = IkMatrix::paper_calibrated().entries().to_vec();
        x.push(0.037);
        let res = model.resolve(&x).unwrap();
        let (r, j) = stacked(&ev, &res, kind);
        let fast = ev.residual_vector(&res, kind);
        assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "residuals differ");
        for c in 0..9 {
            let (gap, col_max) = column_gap(&ev, &model, &x, &j, c, kind, 0.05);
            assert!(col_max > 1e-3, "column {c} is flat");
            assert!(gap < 1e-6, "{kind:?} column {c}: relative gap {gap:e}");
        }
    }
}

/// With wheel-stage effects (an affine one from its parts, and two effects rewritten on each evaluation)
/// the IK Jacobian is the kernel's forward-mode one along the rewritten speeds: it matches central
/// differences.
#[test]
fn ik_jacobian_with_wheel_stage_effects_matches_central_differences() {
    let runs: Vec<Run> = paper_size().into_iter().step_by(15).collect();
    let cases: [(&[&str], Vec<f64>); 2] = [
        (&["wheel_eccentricity"], vec![0.02, -0.01, 0.01, 0.015, 0.0, -0.02]),
        (&["backlash", "wheel_asymmetry"], vec![0.02, 0.01, 0.03, 0.05, -0.03, 0.02]),
    ];
    for (ids, values) in cases {
        let mut model = Model::ik(IkMatrix::paper_design());
        for id in ids {
            model = model.with_effect(EffectKind::from_id(id, 3).unwrap());
        }
        let ev = Evaluator::for_cost(&model, &runs, CostKind::PATH).unwrap();
        let mut x = IkMatrix::paper_calibrated().entries().to_vec();
        x.extend(&values);
        let (r, j) = stacked(&ev, &model.resolve(&x).unwrap(), CostKind::PATH);
        let fast = ev.residual_vector(&model.resolve(&x).unwrap(), CostKind::PATH);
        assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "{ids:?}: residuals differ");
        // The affine effect's parameters are columns too (its parts); two wheel-stage effects: none.
        let carried = if ids.len() == 1 { values.len() } else { 0 };
        assert_eq!(j.ncols(), 9 + carried, "{ids:?}");
        for c in 0..9 + carried {
            let (gap, col_max) = column_gap(&ev, &model, &x, &j, c, CostKind::PATH, 0.05);
            assert!(col_max > 1e-3, "column {c} is flat");
            assert!(gap < 1e-6, "{ids:?} column {c}: relative gap {gap:e}");
        }
    }
}

/// The forward-mode walk's Jacobian (IK entries and the effect parameters it carries) against central
/// differences of the evaluator's residuals, for twist-stage effects alone and mixed with a sensor offset,
/// an affine wheel-stage effect, measured stamps and a clock lag (whose column is left to the caller).
#[test]
fn forward_jacobian_matches_central_differences() {
    use crate::evaluate::ModelBlock;
    let runs = jittered_runs(5);
    let cases: Vec<(Vec<&str>, Vec<f64>, usize)> = vec![
        (vec!["rotation_slip"], vec![0.12], 1),
        (vec!["turn_scrub"], vec![-0.13], 1),
        (vec!["world_drift"], vec![0.004, -0.003], 2),
        (vec!["learned:body"], vec![0.05, 0.02, 0.1, -0.05, 0.03, 0.02, -0.01, 0.015, 0.01], 9),
        (vec!["learned:world"], vec![0.003, -0.002, 0.01, -0.02, 0.015, -0.01], 6),
        (vec!["learned:time"], vec![0.001, -0.0005, 0.002, 0.003], 4),
        (vec!["sensor_offset_yaw", "rotation_slip"], vec![0.03, -0.02, 0.05, 0.1], 4),
        (vec!["wheel_eccentricity", "world_drift"], vec![0.02, -0.01, 0.01, 0.015, 0.0, -0.02, 0.004, 0.002], 8),
        (vec!["sample_timing", "learned:ground_truth", "rotation_slip"], vec![0.02, 0.01, -0.03, 0.08], 4),
        (vec!["time_offset", "rotation_slip"], vec![0.03, 0.1], 1),
        (
            vec!["rotation_slip", "learned:world", "learned:body"],
            [vec![-0.7, 0.003, -0.002, 0.01, -0.02, 0.015, -0.01], vec![0.01; 9]].concat(),
            16,
        ),
        // A user's twist-stage effect: its hook's slopes by differences.
        (vec!["spin", "world_drift"], vec![0.02, 0.004, 0.002], 3),
    ];
    for (ids, values, carried) in cases {
        for kind in [CostKind::EndPose, CostKind::PATH, CostKind::Path { every: 4, heading_weight_m_per_rad: 0.5 }] {
            let mut model = Model::ik(IkMatrix::paper_design());
            for id in &ids {
                let e = match *id {
                    "spin" => EffectKind::Custom(std::sync::Arc::new(Spin)),
                    id => EffectKind::from_id(id, 3).unwrap(),
                };
                model = model.with_effect(e);
            }
            let mut x = IkMatrix::paper_calibrated().entries().to_vec();
            x.extend(&values);
            let ev = Evaluator::for_cost(&model, &runs, kind).unwrap();
            let mut rows: Vec<(Vec<f64>, DMatrix<f64>, Vec<usize>)> = Vec::new();
            ev.forward_jacobian_blocks(&model, &x, kind, &mut |b: ModelBlock<'_>| {
                rows.push((b.residuals.to_vec(), b.jacobian.clone(), b.covered.to_vec()))
            })
            .unwrap();
            assert_eq!(rows.len(), runs.len());
            let covered = rows[0].2.clone();
            assert_eq!(covered.len(), carried, "{ids:?}");
            let r: Vec<f64> = rows.iter().flat_map(|b| b.0.clone()).collect();
            let fast = ev.residual_vector(&model.resolve(&x).unwrap(), kind);
            assert!(r.iter().zip(&fast).all(|(a, b)| (a - b).abs() < 1e-12), "{ids:?} {kind:?}: residuals differ");
            let columns: Vec<usize> = (0..9).chain(covered.iter().copied()).collect();
            for (c, &g) in columns.iter().enumerate() {
                let h = 1e-6 * x[g].abs().max(if g < 9 { 0.05 } else { 1e-2 });
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[g] += h;
                xm[g] -= h;
                let rp = ev.residual_vector(&model.resolve(&xp).unwrap(), kind);
                let rm = ev.residual_vector(&model.resolve(&xm).unwrap(), kind);
                let col: Vec<f64> =
                    rows.iter().flat_map(|b| b.1.column(c).iter().copied().collect::<Vec<_>>()).collect();
                let col_max = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!(col_max > 1e-6, "{ids:?} column {g} is flat");
                for i in 0..r.len() {
                    let fd = (rp[i] - rm[i]) / (2.0 * h);
                    let gap = (fd - col[i]).abs() / col_max;
                    assert!(gap < 1e-6, "{ids:?} {kind:?} column {g} row {i}: {fd} vs {} ({gap:e})", col[i]);
                }
            }
        }
    }
}
