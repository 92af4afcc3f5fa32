#pragma once
// Included by the files that compile AVX-512 code (called only where the CPU runs it, checked at
// run time). AVX512_TARGET: the instruction sets that code may use (F, DQ, BW and VL);
// AVX512_INLINE: a helper of such code, forced inline into its callers.
#define AVX512_TARGET __attribute__((target("avx512f,avx512dq,avx512bw,avx512vl")))
#define AVX512_INLINE AVX512_TARGET __attribute__((always_inline)) inline

// GCC 12's AVX-512 intrinsics start their results from _mm512_undefined_*() and then warn that
// it is (or may be) used uninitialized (GCC bug 105593, fixed in GCC 13), which -Werror would
// turn into a failed build.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
