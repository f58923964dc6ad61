//! Run-time selection of AVX2 code for the few long numeric loops (stage combinations, error sums,
//! history evaluation, sines): the baseline x86-64 target has 2-wide vectors, AVX2 4-wide, and
//! building for the host CPU would make binaries that fail on older machines.

/// Defines `fn $name` running `$body` compiled for AVX2 (four components per instruction instead of
/// two) when [`avx2_in_use`], and for the baseline x86-64 otherwise; the two agree to rounding.
macro_rules! with_avx2 {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)? $body:block) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            #[inline(always)]
            fn body($($arg: $ty),*) $(-> $ret)? $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                fn avx2($($arg: $ty),*) $(-> $ret)? {
                    body($($arg),*)
                }
                if $crate::simd::avx2_in_use() {
                    // SAFETY: the CPU supports AVX2 (avx2_in_use checks it).
                    return unsafe { avx2($($arg),*) };
                }
            }
            body($($arg),*)
        }
    };
}

/// Whether the AVX2 compilations of the long loops run: on x86-64 CPUs with AVX2, unless
/// the environment variable `QUELL_NO_AVX2` is set (to any value) when this is first asked. With it
/// set, every x86-64 machine rounds the same way. Decided once per process.
pub fn avx2_in_use() -> bool {
    static IN_USE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *IN_USE.get_or_init(|| {
        #[cfg(target_arch = "x86_64")]
        {
            std::env::var_os("QUELL_NO_AVX2").is_none() && std::arch::is_x86_feature_detected!("avx2")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    })
}
