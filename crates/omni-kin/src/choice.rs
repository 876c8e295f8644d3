//! Closed choices (a preset, an objective, a kind of base model, …) with one stable id per variant, used
//! alike by the command line (flag values and their help), model files, JSON and Python.
//!
//! A fieldless enum declares its table once with [`choice!`](crate::choice!): id and one line for users
//! per variant, and optionally its default. That gives it the inherent `ALL`, `id()` and `describe()`,
//! [`Choice`], `FromStr` (the id; `-` and `_` are the same, so the command line's kebab-case `end-pose`
//! reads as `end_pose`), `Display` (the id) and `Default`.
//!
//! ```
//! use omni_kin::choice::Choice;
//! use omni_kin::cost::CostName;
//! assert_eq!("end-pose".parse::<CostName>(), Ok(CostName::EndPose));
//! assert_eq!(CostName::EndPose.to_string(), "end_pose");
//! assert_eq!(CostName::EndPose.flag_value(), "end-pose");
//! let err = "fast".parse::<CostName>().unwrap_err();
//! assert_eq!(format!("cost {err}"), r#"cost "fast": expected "end_pose" or "path""#);
//! ```

use thiserror::Error;

/// A fieldless enum whose variants have stable ids. Implement it with [`choice!`](crate::choice!).
pub trait Choice: Copy + PartialEq + Sized + Send + Sync + 'static {
    /// Every variant, in the order help lists them.
    const ALL: &'static [Self];
    /// The default, when there is one (messages name it first).
    const DEFAULT: Option<Self>;

    /// Stable id, snake_case: `end_pose`. Model files, JSON and Python use it as is; the command line
    /// spells it in kebab-case ([`Choice::flag_value`]).
    fn id(self) -> &'static str;

    /// One line for users (command-line help), without a final period.
    fn describe(self) -> &'static str;

    /// The id as a command-line value: kebab-case (`end-pose`), as clap spells enum values.
    fn flag_value(self) -> String {
        self.id().replace('_', "-")
    }

    /// Other names the variant answers to (short forms), beside its id. Default none.
    fn aliases(self) -> &'static [&'static str] {
        &[]
    }

    /// The variant with this id or alias (`-` and `_` alike), or an error listing the ids.
    fn from_id(s: &str) -> Result<Self, UnknownChoice> {
        let wanted = s.replace('-', "_");
        Self::ALL
            .iter()
            .copied()
            .find(|v| v.id() == wanted || v.aliases().iter().any(|a| a.replace('-', "_") == wanted))
            .ok_or_else(|| UnknownChoice { got: s.to_string(), expected: expected_ids::<Self>() })
    }
}

/// The ids quoted, the default first: `"default" or "paper"`, `"a", "b" or "c"`.
fn expected_ids<T: Choice>() -> String {
    let ids: Vec<String> = T::DEFAULT
        .into_iter()
        .chain(T::ALL.iter().copied().filter(|v| Some(*v) != T::DEFAULT))
        .map(|v| format!("{:?}", v.id()))
        .collect();
    match ids.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => ids.join(""),
    }
}

/// A name that is none of a choice's ids. Displays as `"x": expected "a" or "b"`; callers say what was
/// being chosen (`preset "x": …`, `kinematics = "x": …`).
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("{got:?}: expected {expected}")]
pub struct UnknownChoice {
    /// The name given.
    pub got: String,
    /// The ids, quoted, the default first: `"default" or "paper"`.
    pub expected: String,
}

/// Implements the inherent `ALL` (array), `id()` and `describe()`, [`Choice`], `FromStr`, `Display` and
/// (with `default = Variant`) `Default` for a fieldless enum from one table:
/// `Variant => "id": "one line for users"`, every variant once, in help order.
///
/// ```
/// #[derive(Clone, Copy, Debug, PartialEq, Eq)]
/// enum Side { Left, Right }
/// omni_kin::choice!(Side, default = Left, {
///     Left => "left": "To the left",
///     Right => "right": "To the right",
/// });
/// assert_eq!("right".parse::<Side>(), Ok(Side::Right));
/// assert_eq!(Side::ALL.map(Side::id), ["left", "right"]);
/// assert_eq!(Side::default(), Side::Left);
/// ```
#[macro_export]
macro_rules! choice {
    ($t:ty, default = $default:ident, { $($variant:ident => $id:literal : $describe:literal),+ $(,)? }) => {
        $crate::choice!(@impl $t, Some(Self::$default), { $($variant => $id : $describe),+ });
        impl ::core::default::Default for $t {
            fn default() -> Self {
                Self::$default
            }
        }
    };
    ($t:ty, { $($variant:ident => $id:literal : $describe:literal),+ $(,)? }) => {
        $crate::choice!(@impl $t, None, { $($variant => $id : $describe),+ });
    };
    (@impl $t:ty, $default:expr, { $($variant:ident => $id:literal : $describe:literal),+ }) => {
        impl $t {
            /// Every variant, in the order help lists them.
            pub const ALL: [Self; [$($id),+].len()] = [$(Self::$variant),+];

            /// Stable id (snake_case), as model files, JSON, Python and (in kebab-case) the command line
            /// write it.
            pub fn id(self) -> &'static str {
                match self {
                    $(Self::$variant => $id),+
                }
            }

            /// One line for users (command-line help).
            pub fn describe(self) -> &'static str {
                match self {
                    $(Self::$variant => $describe),+
                }
            }
        }
        impl $crate::choice::Choice for $t {
            const ALL: &'static [Self] = &<$t>::ALL;
            const DEFAULT: ::core::option::Option<Self> = $default;
            fn id(self) -> &'static str {
                <$t>::id(self)
            }
            fn describe(self) -> &'static str {
                <$t>::describe(self)
            }
        }
        impl ::core::str::FromStr for $t {
            type Err = $crate::choice::UnknownChoice;
            fn from_str(s: &str) -> ::core::result::Result<Self, Self::Err> {
                <Self as $crate::choice::Choice>::from_id(s)
            }
        }
        impl ::core::fmt::Display for $t {
            fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                f.write_str(<$t>::id(*self))
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    enum Three {
        A,
        BeeCee,
        D,
    }
    crate::choice!(Three, default = D, {
        A => "a": "First",
        BeeCee => "bee_cee": "Second",
        D => "d": "Third",
    });

    #[test]
    fn ids_round_trip_and_errors_list_the_default_first() {
        for v in Three::ALL {
            assert_eq!(v.to_string().parse::<Three>(), Ok(v));
            assert_eq!(v.flag_value().parse::<Three>(), Ok(v));
        }
        assert_eq!(Three::BeeCee.flag_value(), "bee-cee");
        assert_eq!(Three::default(), Three::D);
        let e = "x".parse::<Three>().unwrap_err();
        assert_eq!(e.to_string(), r#""x": expected "d", "a" or "bee_cee""#);
        assert_eq!(<Three as Choice>::ALL, &Three::ALL);
    }
}
