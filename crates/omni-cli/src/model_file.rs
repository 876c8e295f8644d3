//! Model files: a fitted model as human-readable TOML that `omnical eval --model FILE` reads back
//! exactly (floats are written in shortest round-trip form).
//!
//! ```toml
//! format = "omnical-model/1"
//! kinematics = "ik"                      # or "geometry"
//! wheel_names = ["wheel_a", "wheel_b", "wheel_c"]
//! # ik: rows vx (m/s), vy (m/s), ω (rad/s); columns: wheel speeds (rad/s)
//! matrix = [[-0.0883, 0.0, 0.0873], [0.0523, -0.1008, 0.0536], [0.2357, 0.2339, 0.2349]]
//! design_matrix = [[...], [...], [...]]  # the search centre
//!
//! [integration]
//! step = "fixed"                         # or "stamps"
//! dt_s = 0.01                            # optional: default each run's median interval
//! scheme = "exact_arc"                   # or "euler" (the paper's Eq. 1)
//!
//! [[effects]]
//! id = "time_offset"
//! params = { tau_s = 0.02 }
//!
//! [fit]                                  # optional: how it was made (not read back into the model)
//! ```
//! `geometry` models store `[[wheels]]` (radius_m, distance_m, angle_rad, drive_offset_rad,
//! roller_angle_rad) and `[[design_wheels]]` instead of the matrices; `skid` models `[[design_wheels]]`
//! and a `[skid]` table (r_right_m, r_left_m, y_icr_left_m, y_icr_right_m, x_icr_m).

use omni_kin::effect::Effect;
use omni_kin::{BaseRecord, EffectKind, FittedModel, Integration, KinematicsKind, Model, Wheel};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use thiserror::Error;

/// Format tag written in every model file.
pub const FORMAT: &str = "omnical-model/1";

/// A problem reading or writing a model file.
#[derive(Debug, Error)]
pub enum ModelFileError {
    /// The file could not be read or written.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// The OS error (its text is in this message, so it is not chained again).
        error: std::io::Error,
    },
    /// The file is not valid TOML of the expected shape.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// What is wrong (from the TOML parser, with line and column).
        message: String,
    },
    /// The contents do not make a valid model.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// Why a fitted model does not make model file text.
#[derive(Debug, Error)]
pub enum ModelTextError {
    /// The model's base kinematics cannot be written as the file's keys.
    #[error(transparent)]
    Record(#[from] omni_kin::KinError),
    /// The TOML serializer refused the file.
    #[error(transparent)]
    Serialize(#[from] toml::ser::Error),
}

/// One effect in a model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EffectEntry {
    /// Effect id, e.g. `time_offset`.
    pub id: String,
    /// Parameter values by name (unqualified), in the effect's units.
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
}

/// Longest fixed integration step a model file may declare: one wheel sample per second. s.
pub const MAX_STEP_S: f64 = 1.0;

/// The file's shape (TOML). An unknown key is an error (a misspelt `[[effect]]` would otherwise be a model
/// without its effects).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Always [`FORMAT`].
    pub format: String,
    /// `ik` or `geometry` ([`KinematicsKind`]).
    pub kinematics: String,
    /// Wheel (joint) names in column order.
    pub wheel_names: Vec<String>,
    /// Fitted IK matrix (ik models): 3 rows × N wheels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<Vec<Vec<f64>>>,
    /// Design IK matrix (ik models).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design_matrix: Option<Vec<Vec<f64>>>,
    /// Fitted wheels (geometry models).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wheels: Option<Vec<Wheel>>,
    /// Design wheels (geometry models).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design_wheels: Option<Vec<Wheel>>,
    /// A skid-steer base's parameters (`skid` models): `r_right_m`, `r_left_m`, `y_icr_left_m`,
    /// `y_icr_right_m`, `x_icr_m`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skid: Option<omni_kin::kinematics::SkidRecord>,
    /// Integration settings.
    pub integration: Integration,
    /// Effects in pipeline order.
    #[serde(default)]
    pub effects: Vec<EffectEntry>,
    /// How the model was made (free-form summary; ignored when reading but for `interrupted = true`,
    /// which every command that reads the model says, see [`ModelFile::interrupted`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fit: Option<toml::Table>,
    /// How far to trust the odometry: the noise model `train` fits with the calibration (issue 46; read by
    /// `eval` and `export --robot-config`, see [`read_noise`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<omni_kin::noise::OdometryNoise>,
}

impl ModelFile {
    /// The file form of a fitted model.
    pub fn from_fitted(f: &FittedModel, fit: Option<toml::Table>) -> Result<Self, omni_kin::KinError> {
        let nb = f.model.n_base();
        let BaseRecord { wheel_names, matrix, design_matrix, wheels, design_wheels, skid } =
            f.model.kinematics.record(&f.params[..nb])?;
        let effects = f
            .model
            .effects
            .iter()
            .zip(f.model.effect_ranges())
            .map(|(e, r)| EffectEntry {
                id: e.id().to_string(),
                params: e.params().iter().map(|p| p.name.clone()).zip(f.params[r].iter().copied()).collect(),
            })
            .collect();
        Ok(Self {
            format: FORMAT.into(),
            kinematics: f.model.kinematics.id().into(),
            wheel_names,
            matrix,
            design_matrix,
            wheels,
            design_wheels,
            skid,
            integration: f.model.integration,
            effects,
            fit,
            noise: None,
        })
    }

    /// The fitted model this file describes. Errors name the offending key.
    pub fn to_fitted(&self) -> Result<FittedModel, String> {
        if self.format != FORMAT {
            return Err(format!("format is {:?}, expected {FORMAT:?}", self.format));
        }
        let kind: KinematicsKind = self.kinematics.parse().map_err(|e| format!("kinematics = {e}"))?;
        let (kinematics, mut params) = self.base_record().read(kind).map_err(|e| e.to_string())?;
        let n_wheels = kinematics.n_wheels();
        if self.wheel_names.len() != n_wheels {
            return Err(format!("wheel_names has {} names for {n_wheels} wheels", self.wheel_names.len()));
        }
        if let omni_kin::StepMode::Fixed { dt_s: Some(dt) } = self.integration.step
            && !(dt > 0.0 && dt <= MAX_STEP_S)
        {
            return Err(format!(
                "integration dt_s = {dt}: the fixed step is the time of one wheel sample in seconds, above 0 and at \
                 most {MAX_STEP_S} s (the paper's is 0.010); leave it out to take each run's median interval"
            ));
        }
        let mut model = Model { kinematics, effects: Vec::new(), integration: self.integration };
        for (i, entry) in self.effects.iter().enumerate() {
            let e = EffectKind::from_id(&entry.id, n_wheels).map_err(|e| format!("effects[{i}]: {e}"))?;
            let specs = e.params();
            for name in entry.params.keys() {
                if !specs.iter().any(|s| &s.name == name) {
                    let known: Vec<&str> = specs.iter().map(|s| s.name.as_str()).collect();
                    return Err(format!(
                        "effects[{i}] ({}): unknown parameter {name:?}; known: {}",
                        entry.id,
                        known.join(", ")
                    ));
                }
            }
            for s in &specs {
                match entry.params.get(&s.name) {
                    Some(v) => params.push(*v),
                    // A term added to a learned family after the file was written (the `world` family's
                    // grain, 2026-12): the file's correction did not have it, which is its null.
                    None if entry.id.starts_with(omni_kin::effect::learned::PREFIX) => params.push(s.null),
                    None => {
                        return Err(format!(
                            "effects[{i}] ({}): missing parameter {:?} ({})",
                            entry.id, s.name, s.unit
                        ));
                    }
                }
            }
            model.effects.push(e);
        }
        FittedModel::new(model, params).map_err(|e| e.to_string())
    }

    /// Whether the `[fit]` table marks the model `interrupted = true`: `train` was stopped by Ctrl-C and
    /// wrote the best model found so far.
    pub fn interrupted(&self) -> bool {
        self.fit.as_ref().and_then(|t| t.get("interrupted")).and_then(toml::Value::as_bool).unwrap_or(false)
    }

    /// The keys that describe the base kinematics.
    fn base_record(&self) -> BaseRecord {
        BaseRecord {
            wheel_names: self.wheel_names.clone(),
            matrix: self.matrix.clone(),
            design_matrix: self.design_matrix.clone(),
            wheels: self.wheels.clone(),
            design_wheels: self.design_wheels.clone(),
            skid: self.skid,
        }
    }

    /// TOML text. Fails only with [`ModelTextError::Serialize`].
    pub fn to_toml(&self) -> Result<String, ModelTextError> {
        let body = toml::to_string(self)?;
        Ok(format!("# omnical model file: see docs/formats.md\n{body}"))
    }
}

/// Read a model file; a model marked `interrupted = true` (a `train` stopped by Ctrl-C) is read with a
/// warning on stderr that says so ([`interrupted_warning`]), for every command that takes it.
pub fn read(path: &Path) -> Result<FittedModel, ModelFileError> {
    let (model, interrupted) = read_marked(path)?;
    if interrupted {
        tracing::warn!("{}", interrupted_warning(path));
    }
    Ok(model)
}

/// Read a model file, printing nothing: the model, and whether its `[fit]` table marks it interrupted
/// ([`ModelFile::interrupted`]).
pub fn read_marked(path: &Path) -> Result<(FittedModel, bool), ModelFileError> {
    let name = path.display().to_string();
    let text =
        std::fs::read_to_string(path).map_err(|source| ModelFileError::Io { path: name.clone(), error: source })?;
    parse(&text).map_err(|e| match e {
        ParseFailure::Toml(message) => ModelFileError::Parse { path: name.clone(), message },
        ParseFailure::Model(message) => ModelFileError::Invalid { path: name.clone(), message },
    })
}

/// The noise model a model file holds (`None`: the file has none, e.g. written before issue 46 or by hand;
/// `design` and `paper` have none).
pub fn read_noise(path: &Path) -> Result<Option<omni_kin::noise::OdometryNoise>, ModelFileError> {
    let name = path.display().to_string();
    let text =
        std::fs::read_to_string(path).map_err(|source| ModelFileError::Io { path: name.clone(), error: source })?;
    let file: ModelFile = toml::from_str(&text)
        .map_err(|e| ModelFileError::Parse { path: name, message: crate::toml_error::locate(&text, &e) })?;
    Ok(file.noise)
}

/// What a command says when it reads a model marked interrupted: the file, why it is not a finished fit,
/// and what to do.
pub fn interrupted_warning(path: &Path) -> String {
    format!("{}: {INTERRUPTED_REASON}; train again without stopping it before relying on this model", path.display())
}

/// Why a model marked interrupted is not a finished fit (the words of [`interrupted_warning`] and of
/// `export --robot-config`'s refusal).
pub const INTERRUPTED_REASON: &str = "the model is marked interrupted = true (its training was stopped by Ctrl-C: \
                                      the best model found so far, the search cut short and not polished)";

enum ParseFailure {
    Toml(String),
    Model(String),
}

fn parse(text: &str) -> Result<(FittedModel, bool), ParseFailure> {
    let file: ModelFile = toml::from_str(text).map_err(|e| ParseFailure::Toml(crate::toml_error::locate(text, &e)))?;
    Ok((file.to_fitted().map_err(ParseFailure::Model)?, file.interrupted()))
}

/// The TOML text of a fitted model, with optional fit metadata.
pub fn to_toml(f: &FittedModel, fit: Option<toml::Table>) -> Result<String, ModelTextError> {
    ModelFile::from_fitted(f, fit)?.to_toml()
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::{IkMatrix, RobotGeometry};

    #[test]
    fn round_trip_is_exact() {
        let mut f = FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
            .with_effect(EffectKind::from_id("time_offset", 3).unwrap())
            .with_effect(EffectKind::from_id("wheel_asymmetry", 3).unwrap());
        f.params[0] = -0.08832864769631231;
        f.set("time_offset.tau_s", 0.1 + 0.2).unwrap();
        f.set("wheel_asymmetry.a_b", -1e-17).unwrap();
        let text = to_toml(&f, None).unwrap();
        let back = parse(&text).ok().unwrap().0;
        assert_eq!(
            back.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            f.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(back.model.effects.len(), 2);

        let g = FittedModel::nominal(Model::geometry(RobotGeometry::apr02()));
        let back = parse(&to_toml(&g, None).unwrap()).ok().unwrap().0;
        assert_eq!(back.params, g.params);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Any model (matrix or geometry, any subset of effects, any parameter values, any integration)
        /// written to a file and read back gives the same parameters bit for bit and writes the same text.
        #[test]
        fn model_files_round_trip_exactly(
            geometry in proptest::bool::ANY,
            effects in proptest::sample::subsequence(omni_kin::effect::CATALOGUE.to_vec(), 0..4),
            values in proptest::collection::vec(
                proptest::prop_oneof![
                    -1.0f64..1.0,
                    proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO,
                ],
                64,
            ),
            euler in proptest::bool::ANY,
            dt in proptest::option::of(0.001f64..0.1),
        ) {
            let base = if geometry { Model::geometry(RobotGeometry::apr02()) } else { Model::ik(IkMatrix::paper_design()) };
            let integration = omni_kin::Integration {
                step: omni_kin::StepMode::Fixed { dt_s: dt },
                scheme: if euler { omni_kin::Scheme::Euler } else { omni_kin::Scheme::ExactArc },
            };
            let mut f = FittedModel::nominal(base.with_integration(integration));
            for id in &effects {
                f = f.with_effect(EffectKind::from_id(id, 3).unwrap());
            }
            // Geometry parameters must stay physical: perturb them relatively; others take any value.
            let nb = f.model.n_base();
            for (i, p) in f.params.iter_mut().enumerate() {
                *p = if geometry && i < nb { *p * (1.0 + 0.1 * values[i].clamp(-1.0, 1.0)) } else { values[i] };
            }
            let f = FittedModel::new(f.model.clone(), f.params.clone()).unwrap();
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("m.toml");
            let text = to_toml(&f, None).unwrap();
            crate::atomic::write_atomic(&path, text.as_bytes()).unwrap();
            let back = read(&path).unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            proptest::prop_assert_eq!(bits(&back.params), bits(&f.params));
            proptest::prop_assert_eq!(to_toml(&back, None).unwrap(), text);
        }
    }

    /// `interrupted = true` in `[fit]` (what `train` writes after Ctrl-C) marks the model; no `[fit]`, or
    /// one without it, does not.
    #[test]
    fn the_fit_table_marks_an_interrupted_model() {
        let f = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
        let fit = |interrupted: bool| {
            let mut t = toml::Table::new();
            t.insert("preset".into(), "default".into());
            if interrupted {
                t.insert("interrupted".into(), true.into());
            }
            Some(t)
        };
        let marked = |fit: Option<toml::Table>| parse(&to_toml(&f, fit).unwrap()).ok().unwrap().1;
        assert!(marked(fit(true)));
        assert!(!marked(fit(false)));
        assert!(!marked(None));
    }

    #[test]
    fn bad_effect_parameter_is_named() {
        let f = FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
            .with_effect(EffectKind::from_id("time_offset", 3).unwrap());
        let text = to_toml(&f, None).unwrap().replace("tau_s", "tau");
        match parse(&text) {
            Err(ParseFailure::Model(m)) => {
                assert_eq!(m, "effects[0] (time_offset): unknown parameter \"tau\"; known: tau_s")
            }
            _ => panic!("expected a model error"),
        }
    }

    #[test]
    fn unknown_keys_and_impossible_steps_are_refused() {
        let f = FittedModel::nominal(Model::ik(IkMatrix::paper_design()));
        let text = to_toml(&f, None).unwrap();
        let message = |text: &str| match parse(text) {
            Err(ParseFailure::Toml(m) | ParseFailure::Model(m)) => m,
            Ok(_) => panic!("accepted:\n{text}"),
        };
        let m = message(&format!("{text}\n[[effect]]\nid = \"time_offset\"\n"));
        assert!(m.contains("unknown field `effect`"), "{m}");
        let zero = text.replace("[integration]\n", "[integration]\ndt_s = 0.0\n");
        assert_eq!(
            message(&zero),
            "integration dt_s = 0: the fixed step is the time of one wheel sample in seconds, above 0 and at most 1 \
             s (the paper's is 0.010); leave it out to take each run's median interval"
        );
        assert!(
            message(&text.replace("[integration]\n", "[integration]\ndt_s = 10.0\n"))
                .starts_with("integration dt_s = 10:")
        );
        assert!(parse(&text.replace("[integration]\n", "[integration]\ndt_s = 0.01\n")).is_ok());
    }
}
