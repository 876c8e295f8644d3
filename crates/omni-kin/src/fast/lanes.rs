//! Lane-wise arithmetic on a group's eight runs, and the SIMD path that does it, chosen at run time:
//!
//! - [`SimdPath::Avx512`]: one 512-bit vector of 8 f64 per quantity (AVX-512F + FMA, `pulp`'s `x86::V4`);
//! - [`SimdPath::Avx2`]: two 256-bit vectors per quantity (AVX2 + FMA, `pulp`'s `x86::V3_512b`);
//! - [`SimdPath::Portable`]: plain arrays with [`f64::mul_add`] (a fused multiply-add, in hardware where
//!   the CPU has one).
//!
//! The three do the same operations on each lane, every multiply-add fused, so their results are the same
//! bits (tested); only the speed differs. The best path the CPU has is taken (checked once, no
//! `-C target-cpu` needed), under a process-wide ceiling ([`limit_simd_path`]; the command line sets it
//! from `OMNICAL_SIMD`) that benchmarks use to compare paths on one machine.
//!
//! [`Portable`] (unfused) is the arithmetic of the twist-stage walk, which keeps its own bits.

use super::{LANES, Lanes};
use std::sync::atomic::{AtomicU8, Ordering};

/// The lane arithmetic the step kernel uses, narrowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SimdPath {
    /// Plain arrays, fused multiply-adds by [`f64::mul_add`].
    Portable,
    /// Two 4-lane AVX2 + FMA vectors (x86-64-v3).
    Avx2,
    /// One 8-lane AVX-512 vector (x86-64-v4).
    Avx512,
}

/// The ceiling set by [`limit_simd_path`] (`u8::MAX`: none).
static CEILING: AtomicU8 = AtomicU8::new(u8::MAX);

/// Caps the path the kernel takes at `path` for the rest of the process (a wider path than the CPU has is
/// never taken). The results do not depend on it; only the speed does.
pub fn limit_simd_path(path: SimdPath) {
    CEILING.store(path as u8, Ordering::Relaxed);
}

impl SimdPath {
    /// Every path, narrowest first.
    pub const ALL: [SimdPath; 3] = [SimdPath::Portable, SimdPath::Avx2, SimdPath::Avx512];

    /// The name `OMNICAL_SIMD` takes: `portable`, `avx2` or `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Portable => "portable",
            SimdPath::Avx2 => "avx2",
            SimdPath::Avx512 => "avx512",
        }
    }

    /// The path named `name` (see [`Self::name`]; case-insensitive).
    pub fn from_name(name: &str) -> Option<SimdPath> {
        Self::ALL.into_iter().find(|p| p.name().eq_ignore_ascii_case(name.trim()))
    }

    /// True when this CPU has the instructions of the path.
    pub fn is_available(self) -> bool {
        match self {
            SimdPath::Portable => true,
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx2 => pulp::x86::V3::try_new().is_some(),
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx512 => pulp::x86::V4::try_new().is_some(),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The paths this CPU has, narrowest first.
    pub fn available() -> Vec<SimdPath> {
        Self::ALL.into_iter().filter(|p| p.is_available()).collect()
    }

    /// The path the kernel takes: the widest this CPU has, capped by [`limit_simd_path`].
    pub fn selected() -> SimdPath {
        let ceiling = CEILING.load(Ordering::Relaxed);
        (Self::ALL.into_iter().rev()).find(|p| (*p as u8) <= ceiling && p.is_available()).unwrap_or(SimdPath::Portable)
    }
}

/// Lane-wise arithmetic on a group's runs.
pub(super) trait LaneOps: Copy {
    type V: Copy;
    fn splat(self, v: f64) -> Self::V;
    fn load(self, a: Lanes) -> Self::V;
    fn store(self, v: Self::V) -> Lanes;
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a b + c` (fused where the type says so).
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// `c − a b` (fused where the type says so).
    fn neg_mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
}

/// Plain arrays, unfused (`a b + c` rounded twice): the twist-stage walk's arithmetic.
#[derive(Clone, Copy)]
pub(super) struct Portable;

/// Plain arrays with fused multiply-adds: the kernel's [`SimdPath::Portable`], the same bits as the vectors.
#[derive(Clone, Copy)]
pub(super) struct Fused;

/// The lane-wise operations of a plain-array type, `$fma` giving `a b + c`.
macro_rules! array_lane_ops {
    ($t:ty, $fma:expr) => {
        impl LaneOps for $t {
            type V = Lanes;
            #[inline(always)]
            fn splat(self, v: f64) -> Lanes {
                [v; LANES]
            }
            #[inline(always)]
            fn load(self, a: Lanes) -> Lanes {
                a
            }
            #[inline(always)]
            fn store(self, v: Lanes) -> Lanes {
                v
            }
            #[inline(always)]
            fn add(self, a: Lanes, b: Lanes) -> Lanes {
                std::array::from_fn(|l| a[l] + b[l])
            }
            #[inline(always)]
            fn mul(self, a: Lanes, b: Lanes) -> Lanes {
                std::array::from_fn(|l| a[l] * b[l])
            }
            #[inline(always)]
            fn mul_add(self, a: Lanes, b: Lanes, c: Lanes) -> Lanes {
                let fma: fn(f64, f64, f64) -> f64 = $fma;
                std::array::from_fn(|l| fma(a[l], b[l], c[l]))
            }
            #[inline(always)]
            fn neg_mul_add(self, a: Lanes, b: Lanes, c: Lanes) -> Lanes {
                let fma: fn(f64, f64, f64) -> f64 = $fma;
                std::array::from_fn(|l| fma(-a[l], b[l], c[l]))
            }
        }
    };
}

array_lane_ops!(Portable, |a, b, c| a * b + c);
array_lane_ops!(Fused, f64::mul_add);

/// The lane-wise operations of a `pulp` SIMD type whose `f64s` are eight lanes (`pulp::f64x8`).
macro_rules! pulp_lane_ops {
    ($t:ty) => {
        #[cfg(target_arch = "x86_64")]
        impl LaneOps for $t {
            type V = pulp::f64x8;
            #[inline(always)]
            fn splat(self, v: f64) -> Self::V {
                pulp::Simd::splat_f64s(self, v)
            }
            #[inline(always)]
            fn load(self, a: Lanes) -> Self::V {
                pulp::cast(a)
            }
            #[inline(always)]
            fn store(self, v: Self::V) -> Lanes {
                pulp::cast(v)
            }
            #[inline(always)]
            fn add(self, a: Self::V, b: Self::V) -> Self::V {
                pulp::Simd::add_f64s(self, a, b)
            }
            #[inline(always)]
            fn mul(self, a: Self::V, b: Self::V) -> Self::V {
                pulp::Simd::mul_f64s(self, a, b)
            }
            #[inline(always)]
            fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V {
                pulp::Simd::mul_add_e_f64s(self, a, b, c)
            }
            #[inline(always)]
            fn neg_mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V {
                pulp::Simd::negate_mul_add_e_f64s(self, a, b, c)
            }
        }
    };
}

pulp_lane_ops!(pulp::x86::V3_512b);
pulp_lane_ops!(pulp::x86::V4);
