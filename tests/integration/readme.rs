//! The README's Rust block, line for line (crates/omni-cli/tests/readme.rs checks that each of its lines is
//! here): simulate the paper's robot, fit the matrix from the design, and get the true matrix back.

/// The README's block as the body of a function (its `?` need one returning `Result`); the fitted rows.
/// Not formatted, so that it stays the README's text.
#[rustfmt::skip]
fn readme_block() -> Result<Vec<Vec<f64>>, Box<dyn std::error::Error>> {
    use omnical::kin::{simulate::{SimConfig, simulate}, FittedModel, IkMatrix, Model};
    use omnical::ga::{calibrate::{calibrate, Plan, Preset}, NoopObserver};
    let truth = FittedModel::nominal(Model::ik(IkMatrix::paper_calibrated()));
    let runs = simulate(&SimConfig::default(), &truth, "train/")?;
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let fit = calibrate(&start, &runs, &Plan::preset(Preset::Default, 9), &mut NoopObserver)?;
    println!("{:?}", fit.fitted.ik()?.rows());
    Ok(fit.fitted.ik()?.rows())
}

#[test]
fn readme_rust_block_recovers_the_true_matrix() {
    let rows = readme_block().unwrap();
    let truth = omnical::kin::IkMatrix::paper_calibrated().rows();
    for (fitted, true_row) in rows.iter().zip(&truth) {
        for (f, t) in fitted.iter().zip(true_row) {
            // The simulator's noise leaves each entry within 1 % of the true one's scale (0.1 m, 0.24 rad).
            assert!((f - t).abs() < 1e-3, "fitted {rows:?} vs true {truth:?}");
        }
    }
}
