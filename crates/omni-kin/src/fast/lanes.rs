//! Lane-wise arithmetic on a group's eight runs, and the SIMD path that does it, chosen at run time:
//!
//! - [`SimdPath::Avx512`]: one 512-bit vector of 8 f64 per quantity (AVX-512F + FMA, `pulp`'s `x86::V4`);
//! - [`SimdPath::Avx2`]: one 256-bit vector of 4 f64 per quantity (AVX2 + FMA, `pulp`'s `x86::V3`), a
//!   group walked in two passes;
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
    /// 4-lane AVX2 + FMA vectors, two passes per group (x86-64-v3).
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

/// Lane-wise arithmetic on [`Self::WIDTH`] of a group's runs.
pub(super) trait LaneOps: Copy {
    /// Lanes per value.
    const WIDTH: usize;
    type V: Copy;
    fn splat(self, v: f64) -> Self::V;
    /// The first [`Self::WIDTH`] values of `a`.
    fn load(self, a: &[f64]) -> Self::V;
    /// Writes the lanes of `v` to the first [`Self::WIDTH`] values of `out`.
    fn store(self, v: Self::V, out: &mut [f64]);
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
            const WIDTH: usize = LANES;
            type V = Lanes;
            #[inline(always)]
            fn splat(self, v: f64) -> Lanes {
                [v; LANES]
            }
            #[inline(always)]
            fn load(self, a: &[f64]) -> Lanes {
                std::array::from_fn(|l| a[l])
            }
            #[inline(always)]
            fn store(self, v: Lanes, out: &mut [f64]) {
                out[..LANES].copy_from_slice(&v);
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

/// The lane-wise operations of a `pulp` SIMD type of `$width` lanes, its vector `$v` built from and read
/// to lanes by `$from` and `$to`.
macro_rules! pulp_lane_ops {
    ($t:ty, $width:expr, $v:ty, $from:expr, $to:expr) => {
        #[cfg(target_arch = "x86_64")]
        impl LaneOps for $t {
            const WIDTH: usize = $width;
            type V = $v;
            #[inline(always)]
            fn splat(self, v: f64) -> Self::V {
                pulp::Simd::splat_f64s(self, v)
            }
            #[inline(always)]
            fn load(self, a: &[f64]) -> Self::V {
                let from: fn(&[f64]) -> $v = $from;
                from(&a[..$width])
            }
            #[inline(always)]
            fn store(self, v: Self::V, out: &mut [f64]) {
                let to: fn($v) -> [f64; $width] = $to;
                out[..$width].copy_from_slice(&to(v));
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

// AVX2 + FMA: four lanes per vector, a group walked in two passes (eight lanes as two vectors each would
// not leave the state and the constants in the 16 vector registers).
pulp_lane_ops!(pulp::x86::V3, 4, pulp::f64x4, |a| pulp::f64x4(a[0], a[1], a[2], a[3]), |v| [v.0, v.1, v.2, v.3]);
// AVX-512: a group's eight lanes in one vector.
pulp_lane_ops!(pulp::x86::V4, 8, pulp::f64x8, |a| pulp::f64x8(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]), |v| [
    v.0, v.1, v.2, v.3, v.4, v.5, v.6, v.7
]);
