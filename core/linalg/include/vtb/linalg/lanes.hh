#pragma once
/// \file
/// A node's values as one GCC vector of W doubles (two or four: 3D nodes are padded to four),
/// loaded unaligned and may_alias as the intrinsics' types are, for the V-cycles' sweeps
/// (multigrid.cc, block_multigrid.cc), the tile solves (block_solve.cc) and the tensor filter's
/// vector kernels (core/solvers/src: mismatch_kernel.cc, polar_kernel.cc). Not part of any
/// interface: a file that passes these vectors to a function that is not inlined needs
/// -Wno-psabi (core/*/CMakeLists.txt), and none does.

namespace vtb::detail {

template <int W> struct LaneType;
template <> struct LaneType<2> { typedef double type __attribute__((vector_size(16), aligned(8), may_alias)); };
template <> struct LaneType<4> { typedef double type __attribute__((vector_size(32), aligned(8), may_alias)); };
// Eight: a 3D coarse node (six rigid modes, padded), two AVX2 or four SSE2 operations.
template <> struct LaneType<8> { typedef double type __attribute__((vector_size(64), aligned(8), may_alias)); };
template <int W> using Lane = typename LaneType<W>::type;
/// What comparing two Lane<W> gives: per lane -1 (true) or 0, as 64-bit integers.
template <int W> struct LaneMaskType;
template <> struct LaneMaskType<2> { typedef long type __attribute__((vector_size(16))); };
template <> struct LaneMaskType<4> { typedef long type __attribute__((vector_size(32))); };
template <int W> using LaneMask = typename LaneMaskType<W>::type;
/// W floats, loaded as W doubles (the block V-cycle's stored matrices: half the bytes).
template <int W> struct FloatLaneType;
template <> struct FloatLaneType<2> { typedef float type __attribute__((vector_size(8), aligned(4), may_alias)); };
template <> struct FloatLaneType<4> { typedef float type __attribute__((vector_size(16), aligned(4), may_alias)); };
template <> struct FloatLaneType<8> { typedef float type __attribute__((vector_size(32), aligned(4), may_alias)); };
// Always inlined, so no 32-byte vector crosses a call (core/linalg/CMakeLists.txt: -Wno-psabi).
template <int W> [[gnu::always_inline]] inline Lane<W> load(const double* p) {
  return *reinterpret_cast<const Lane<W>*>(p);
}
template <int W> [[gnu::always_inline]] inline Lane<W> load(const float* p) {
  return __builtin_convertvector(*reinterpret_cast<const typename FloatLaneType<W>::type*>(p), Lane<W>);
}
template <int W> [[gnu::always_inline]] inline void store(double* p, Lane<W> v) {
  *reinterpret_cast<Lane<W>*>(p) = v;
}

} // namespace vtb::detail
