// Vector forms of libm functions for `#pragma omp simd` loops. glibc's libmvec implements exp, expm1, log1p and tanh
// for 2, 4 and 8 doubles at a time, but its header announces them to GCC only under -ffast-math; declaring them
// here lets GCC call them from a vectorized loop without the rest of -ffast-math. They agree with the scalar
// functions to a few units in the last place (glibc documents at most 4 ulp), so a vectorized closure can move a
// result in its last bits. With other compilers the scalar functions are called.
#pragma once
#include <cmath>

// libmvec has had exp since glibc 2.22, expm1 and log1p since 2.35 (Debian 12, Ubuntu 22.04); older systems use
// the scalar ones.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__GLIBC__) && \
    (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 35))
extern "C" {
__attribute__((simd("notinbranch"))) double exp(double) noexcept;
__attribute__((simd("notinbranch"))) double expm1(double) noexcept;
__attribute__((simd("notinbranch"))) double log1p(double) noexcept;
}
#endif
