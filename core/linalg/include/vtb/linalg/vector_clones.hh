#pragma once
// VTB_VECTOR_CLONES: build a hot loop for AVX2 and for the baseline x86-64, picked at load time
// (GCC's ifunc dispatch), so that the default build (baseline instruction set, docs/performance.md)
// still uses 256-bit registers where the machine has them. VTB_VECTOR_CLONES_WIDE adds an AVX-512F
// clone; it is used on the multigrid sweeps alone, where it measured faster (a V-cycle on the 10k
// slab 2.36 -> 2.23 ms), and not globally (the polar rotations measured slower with it).
// AVX-512F implies FMA, so the top-level CMakeLists.txt builds with -ffp-contract=off: no clone
// fuses a multiply and an add, every clone performs the same IEEE operations in the same order,
// and results are bitwise the same on every x86-64 machine. Clang (the fuzz build) and other
// targets compile the baseline alone.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define VTB_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#define VTB_VECTOR_CLONES_WIDE __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define VTB_VECTOR_CLONES
#define VTB_VECTOR_CLONES_WIDE
#endif
