//! The same seed gives bit-identical fits with 1 or several threads.
use crate::common::{dataset, paper_truth, small_config};
use omnical::ga::calibrate::{Plan, Preset, calibrate};
use omnical::ga::observe::NoopObserver;
use omnical::kin::{FittedModel, IkMatrix, Model};

#[test]
fn same_seed_same_bits_across_thread_counts() {
    let truth = paper_truth();
    let (train, _) = dataset(&truth, &small_config(2, 4, 1, 5.0));
    let start = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
    let plan = Plan::preset(Preset::Default, 9).seed(9);
    let fit = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| calibrate(&start, &train, &plan, &mut NoopObserver).expect("calibrate"))
    };
    let a = fit(1);
    let b = fit(2);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&a.fitted.params), bits(&b.fitted.params));
    assert_eq!(a.objective_fitted.to_bits(), b.objective_fitted.to_bits());
}
