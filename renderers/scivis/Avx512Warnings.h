#pragma once
// Included by the files that use AVX-512 intrinsics: GCC 12's start their results from
// _mm512_undefined_*() and then warn that it is (or may be) used uninitialized (GCC bug 105593,
// fixed in GCC 13), which -Werror would turn into a failed build.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
