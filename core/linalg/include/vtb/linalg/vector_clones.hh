#pragma once
// VTB_VECTOR_CLONES: build a hot loop for AVX2 and for the baseline x86-64, picked at load time
// (GCC's ifunc dispatch), so that the default build (baseline instruction set, docs/performance.md) still
// uses 256-bit registers where the machine has them. No clone enables FMA, so every clone
// performs the same IEEE operations in the same order: results are bitwise the same on every
// x86-64 machine. Clang (the fuzz build) and other targets compile the baseline alone.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define VTB_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define VTB_VECTOR_CLONES
#endif
