//! The Python stubs' closed choices (issue 47 item 3): each `Literal` alias of `_omnical.pyi` holds exactly
//! what the library's choice table accepts (its ids, an id with `_` also spelt with `-`, and its aliases),
//! so a choice added in Rust fails here until the stub has it.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use omni_ga::calibrate::{Preset, Unexcited};
use omni_kin::cost::CostName;
use omni_kin::lidar::LidarModel;
use omni_kin::reference::ReferenceKind;
use omni_kin::{Choice, KinematicsKind};
use std::collections::BTreeSet;

/// The values of `alias = Literal[...]` in the stub file.
fn literal(stub: &str, alias: &str) -> BTreeSet<String> {
    let line = stub
        .lines()
        .find(|l| l.starts_with(&format!("{alias} = Literal[")))
        .unwrap_or_else(|| panic!("_omnical.pyi has no {alias} = Literal[...]"));
    let inner = line.split_once('[').unwrap().1.trim_end_matches(']');
    inner.split(',').map(|v| v.trim().trim_matches('"').to_string()).collect()
}

/// What the choice table accepts.
fn accepted<T: Choice>() -> BTreeSet<String> {
    T::ALL
        .iter()
        .flat_map(|v| {
            let id = v.id().to_string();
            let mut spellings = vec![id.clone(), id.replace('_', "-")];
            spellings.extend(v.aliases().iter().map(|a| a.to_string()));
            spellings
        })
        .collect()
}

#[test]
fn every_closed_choice_of_the_stubs_is_its_tables() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../omni-py/python/omnical/_omnical.pyi");
    let stub = std::fs::read_to_string(path).unwrap();
    assert_eq!(literal(&stub, "_Kinematics"), accepted::<KinematicsKind>());
    assert_eq!(literal(&stub, "_Preset"), accepted::<Preset>());
    assert_eq!(literal(&stub, "_Objective"), accepted::<CostName>());
    assert_eq!(literal(&stub, "_Unexcited"), accepted::<Unexcited>());
    assert_eq!(literal(&stub, "_GtKind"), accepted::<ReferenceKind>());
    assert_eq!(literal(&stub, "_LidarModel"), accepted::<LidarModel>());
    // Each keyword that takes one of them is typed with it.
    for (keyword, alias) in [
        ("preset", "_Preset"),
        ("objective", "Optional[_Objective]"),
        ("unexcited", "Optional[_Unexcited]"),
        ("gt_kind", "Optional[_GtKind]"),
        ("lidar_model", "_LidarModel"),
        ("kinematics", "_Kinematics"),
    ] {
        let typed = format!("{keyword}: {alias}");
        assert!(stub.contains(&typed), "_omnical.pyi: {keyword} is not typed {alias}");
        assert!(!stub.contains(&format!("{keyword}: str")), "_omnical.pyi: {keyword} is still a plain str");
    }
}
