// Eigen, pinned to the baseline x86-64 instruction set (SSE2) whatever the build's
// -march: every revcol source includes Eigen through this header.
//
// Why: Eigen picks its packet width and its multiply-add from the compiler's ISA macros
// (__AVX__, __FMA__, ...). With AVX its reductions (dot products, matrix products) sum in
// four lanes instead of two, and with FMA its products are fused: other roundings, other
// bits. revcol's own arithmetic gives the same bits on any x86-64 level (-ffp-contract=off,
// no reassociation, double_double.hpp's exact products either way), so a build for the host
// (CMake REVCOL_ISA=auto or x86-64-v3) would differ from the baseline build only through Eigen. Hiding
// the macros while Eigen/Core configures itself keeps its code paths those of a baseline
// build; the surrounding code still compiles for the host (Eigen's SSE2 intrinsics are
// valid there). test_engine_hash's group cases go through Eigen (ExactCollision) and hold
// the same constants in both builds; .ci/run builds both.
#pragma once

#if defined(EIGEN_CORE_H) || defined(EIGEN_CORE_MODULE_H)
#error "include Eigen only through revcol/eigen.hpp (it pins Eigen's instruction set)"
#endif

#pragma push_macro("__SSE3__")
#pragma push_macro("__SSSE3__")
#pragma push_macro("__SSE4_1__")
#pragma push_macro("__SSE4_2__")
#pragma push_macro("__AVX__")
#pragma push_macro("__AVX2__")
#pragma push_macro("__FMA__")
#pragma push_macro("__F16C__")
#pragma push_macro("__AVX512F__")
#undef __SSE3__
#undef __SSSE3__
#undef __SSE4_1__
#undef __SSE4_2__
#undef __AVX__
#undef __AVX2__
#undef __FMA__
#undef __F16C__
#undef __AVX512F__
#include <Eigen/Dense>
#pragma pop_macro("__AVX512F__")
#pragma pop_macro("__F16C__")
#pragma pop_macro("__FMA__")
#pragma pop_macro("__AVX2__")
#pragma pop_macro("__AVX__")
#pragma pop_macro("__SSE4_2__")
#pragma pop_macro("__SSE4_1__")
#pragma pop_macro("__SSSE3__")
#pragma pop_macro("__SSE3__")

#if defined(EIGEN_VECTORIZE_AVX) || defined(EIGEN_VECTORIZE_FMA) || defined(EIGEN_VECTORIZE_SSE3)
#error "Eigen configured itself beyond SSE2"
#endif
