//! Lane-wise arithmetic on four runs: AVX2 + FMA vectors where the CPU has them (chosen at run time
//! through `pulp`), plain arrays otherwise.

use super::{LANES, Lanes};

/// Lane-wise arithmetic on four runs: AVX2 + FMA vectors where the CPU has them, plain arrays otherwise.
pub(super) trait LaneOps: Copy {
    type V: Copy;
    fn splat(self, v: f64) -> Self::V;
    fn load(self, a: Lanes) -> Self::V;
    fn store(self, v: Self::V) -> Lanes;
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a b + c` (fused where available).
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// `c − a b` (fused where available).
    fn neg_mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
}

/// Plain `[f64; 4]` arithmetic (no FMA), for CPUs without AVX2 + FMA.
#[derive(Clone, Copy)]
pub(super) struct Portable;

impl LaneOps for Portable {
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
        std::array::from_fn(|l| a[l] * b[l] + c[l])
    }
    #[inline(always)]
    fn neg_mul_add(self, a: Lanes, b: Lanes, c: Lanes) -> Lanes {
        std::array::from_fn(|l| c[l] - a[l] * b[l])
    }
}

#[cfg(target_arch = "x86_64")]
impl LaneOps for pulp::x86::V3 {
    type V = pulp::f64x4;
    #[inline(always)]
    fn splat(self, v: f64) -> Self::V {
        pulp::f64x4(v, v, v, v)
    }
    #[inline(always)]
    fn load(self, a: Lanes) -> Self::V {
        pulp::f64x4(a[0], a[1], a[2], a[3])
    }
    #[inline(always)]
    fn store(self, v: Self::V) -> Lanes {
        [v.0, v.1, v.2, v.3]
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
