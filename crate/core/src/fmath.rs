//! The core's transcendental functions (sine, arc cosine, exponential, logarithm, power …),
//! the same bits in every build: Rust's port of musl's libm.
//!
//! The wasm build's std has no system library: its `f32::sin` and the rest are compiler-builtins'
//! copy of that port, so there these functions are std's. A native build's `f32::sin` calls the
//! platform's C library (glibc here), whose results differ in the last bit for some inputs
//! (measured over 2 million inputs each: `sin` 1.3 %, `acos` 2.3 %, `asin` 9.1 %, `exp` 9.7 %,
//! `ln` 4.7 %, `powf` 9.3 %; `docs/benchmarks-notes-choreo.md`, session 31), so natively they
//! call the [`libm`] crate, and glam does too (its `libm` feature, on for native builds in the
//! core's Cargo.toml). Generate compares dances whose figures can be that close, so the native
//! tests now measure the bits the app ships from these functions. `house_layout` keeps the std
//! methods out of the core. Square root, `powi` and the rounding functions are exact or the
//! same code everywhere and stay std's.

/// A float type libm has the functions of: `f32` (libm's `…f` functions) and `f64`.
pub trait Float: Copy {
    fn libm_sin(self) -> Self;
    fn libm_cos(self) -> Self;
    fn libm_tan(self) -> Self;
    fn libm_asin(self) -> Self;
    fn libm_acos(self) -> Self;
    fn libm_atan(self) -> Self;
    fn libm_atan2(self, x: Self) -> Self;
    fn libm_exp(self) -> Self;
    fn libm_exp2(self) -> Self;
    fn libm_ln(self) -> Self;
    fn libm_log2(self) -> Self;
    fn libm_log10(self) -> Self;
    fn libm_powf(self, e: Self) -> Self;
    fn libm_tanh(self) -> Self;
}

macro_rules! float {
    ($t:ty, $($name:ident: $std:ident / $libm:ident ($($arg:ident),*);)*) => {
        impl Float for $t {
            $(
                #[inline]
                fn $name(self $(, $arg: Self)*) -> Self {
                    // wasm32: std's is compiler-builtins' copy of libm (the same code, one copy
                    // in the module); elsewhere the libm crate, not the C library.
                    #[cfg(target_arch = "wasm32")]
                    return self.$std($($arg),*);
                    #[cfg(not(target_arch = "wasm32"))]
                    return libm::$libm(self $(, $arg)*);
                }
            )*
        }
    };
}

float! {
    f32,
    libm_sin: sin / sinf ();
    libm_cos: cos / cosf ();
    libm_tan: tan / tanf ();
    libm_asin: asin / asinf ();
    libm_acos: acos / acosf ();
    libm_atan: atan / atanf ();
    libm_atan2: atan2 / atan2f (x);
    libm_exp: exp / expf ();
    libm_exp2: exp2 / exp2f ();
    libm_ln: ln / logf ();
    libm_log2: log2 / log2f ();
    libm_log10: log10 / log10f ();
    libm_powf: powf / powf (e);
    libm_tanh: tanh / tanhf ();
}
float! {
    f64,
    libm_sin: sin / sin ();
    libm_cos: cos / cos ();
    libm_tan: tan / tan ();
    libm_asin: asin / asin ();
    libm_acos: acos / acos ();
    libm_atan: atan / atan ();
    libm_atan2: atan2 / atan2 (x);
    libm_exp: exp / exp ();
    libm_exp2: exp2 / exp2 ();
    libm_ln: ln / log ();
    libm_log2: log2 / log2 ();
    libm_log10: log10 / log10 ();
    libm_powf: powf / pow (e);
    libm_tanh: tanh / tanh ();
}

/// `x.sin()`.
#[inline]
pub fn sin<T: Float>(x: T) -> T { x.libm_sin() }
/// `x.cos()`.
#[inline]
pub fn cos<T: Float>(x: T) -> T { x.libm_cos() }
/// `x.sin_cos()`: std's is `(x.sin(), x.cos())`, and so is this one.
#[inline]
pub fn sin_cos<T: Float>(x: T) -> (T, T) { (x.libm_sin(), x.libm_cos()) }
/// `x.tan()`.
#[inline]
pub fn tan<T: Float>(x: T) -> T { x.libm_tan() }
/// `x.asin()`.
#[inline]
pub fn asin<T: Float>(x: T) -> T { x.libm_asin() }
/// `x.acos()`.
#[inline]
pub fn acos<T: Float>(x: T) -> T { x.libm_acos() }
/// `x.atan()`.
#[inline]
pub fn atan<T: Float>(x: T) -> T { x.libm_atan() }
/// `y.atan2(x)`.
#[inline]
pub fn atan2<T: Float>(y: T, x: T) -> T { y.libm_atan2(x) }
/// `x.exp()`.
#[inline]
pub fn exp<T: Float>(x: T) -> T { x.libm_exp() }
/// `x.exp2()`.
#[inline]
pub fn exp2<T: Float>(x: T) -> T { x.libm_exp2() }
/// `x.ln()`.
#[inline]
pub fn ln<T: Float>(x: T) -> T { x.libm_ln() }
/// `x.log2()`.
#[inline]
pub fn log2<T: Float>(x: T) -> T { x.libm_log2() }
/// `x.log10()`.
#[inline]
pub fn log10<T: Float>(x: T) -> T { x.libm_log10() }
/// `x.powf(e)`.
#[inline]
pub fn powf<T: Float>(x: T, e: T) -> T { x.libm_powf(e) }
/// `x.tanh()`.
#[inline]
pub fn tanh<T: Float>(x: T) -> T { x.libm_tanh() }

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_function_is_the_std_one_to_within_an_ulp_or_two() {
        // Not the same bits (that is the point), but the same functions: a mistyped mapping
        // (sin for cos, log2 for ln) is far off.
        for k in 0..2000 {
            let x = (k as f32 - 1000.0) * 0.0093;
            let u = x.clamp(-1.0, 1.0);
            let p = x.abs() + 0.01;
            let close = |a: f32, b: f32| (a - b).abs() <= 4.0 * f32::EPSILON * b.abs().max(1.0);
            assert!(close(sin(x), x.sin()) && close(cos(x), x.cos()) && close(tan(x * 0.1), (x * 0.1).tan()), "{x}");
            assert!(close(sin_cos(x).0, x.sin()) && close(sin_cos(x).1, x.cos()), "{x}");
            assert!(close(asin(u), u.asin()) && close(acos(u), u.acos()) && close(atan(x), x.atan()), "{x}");
            assert!(close(atan2(x, 0.3), x.atan2(0.3)) && close(atan2(-0.3, x), (-0.3f32).atan2(x)), "{x}");
            assert!(close(exp(u), u.exp()) && close(exp2(u), u.exp2()) && close(tanh(x), x.tanh()), "{x}");
            assert!(close(ln(p), p.ln()) && close(log2(p), p.log2()) && close(log10(p), p.log10()), "{x}");
            assert!(close(powf(p, 0.8), p.powf(0.8)) && close(powf(10.0, u), 10f32.powf(u)), "{x}");
            let d = f64::from(x);
            assert!((sin(d) - d.sin()).abs() < 1e-15 && (powf(10.0, d * 0.1) - 10f64.powf(d * 0.1)).abs() < 1e-12, "{x}");
        }
    }
}
