// Box pairs eight at a time: the narrow phase's box-box collider with one pair in each of eight
// AVX lanes.
//
// The per-pair AVX collider (narrow_phase.cpp, CollideBoxesVexInline) puts one pair's faces in
// the lanes; the axis searches fill them, but the rest of a pair (the reference face, the
// incident edge, the two clips and the points) is scalar work on one pair at a time. On the
// base-100 pyramid that was 394 instructions a pair, 10000 pairs a step, and the narrow phase a
// quarter of the one-thread step. Here lane k does pair k's operations, the same ones in the
// same order as CollidePolygonsGeneral's scalar code (branches become lane masks and blends), so
// every manifold is the same bit for bit and the state hashes do not move; NarrowPhaseBoxes tests
// compare the two.
#pragma once

#include "collision/narrow_phase.h"

namespace quadrant {

/// One box pair for CollideBoxBatch: both polygons have four vertices.
struct BoxPair {
  const Polygon* a;
  const Transform* xfA;
  const Polygon* b;
  const Transform* xfB;
  Real speculative;
};

inline constexpr int kBoxBatch = 8;

/// Whether CollideBoxBatch runs its pairs in eight lanes (a float build on a CPU with AVX2);
/// otherwise it collides them one at a time.
bool BoxBatchInLanes();

/// out[k] = CollidePolygons(*pairs[k].a, *pairs[k].xfA, *pairs[k].b, *pairs[k].xfB,
/// pairs[k].speculative) for k < count, 1 <= count <= kBoxBatch, bit for bit.
void CollideBoxBatch(const BoxPair* pairs, int count, Manifold* out);

}  // namespace quadrant
