// Function multiversioning for hot loops. slslam is built without -march so wheels run anywhere;
// baseline x86-64 has neither AVX2 nor the POPCNT instruction (without it a popcount is a library
// call). A function marked with one of these macros is compiled twice and the loader picks the
// version the CPU supports (GCC / Clang target_clones). Each clone computes the same values.
#pragma once

// Not under a sanitizer: the loader runs the clones' resolver before the sanitizer's runtime is
// up, and an instrumented resolver crashes the program at start (SLSLAM_SANITIZED, CMakeLists).
#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(SLSLAM_SANITIZED)
#define SLSLAM_POPCNT_CLONES __attribute__((target_clones("popcnt", "default")))
#define SLSLAM_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
// Loops over long float rows (the stereo row search's costs): AVX-512's 16 lanes where the CPU
// has them.
#define SLSLAM_AVX512_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define SLSLAM_POPCNT_CLONES
#define SLSLAM_AVX2_CLONES
#define SLSLAM_AVX512_CLONES
#endif
