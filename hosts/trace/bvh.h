// hosts/trace/bvh.h — the bounding-volume hierarchy of the host tracer's `--accel bvh`
// (docs/shading.md, "The BVH"): conservative world-space bounds of every primitive and a
// binned-SAH build over them. The traversal is hosts/trace/bvh_walk.h, used by the tracer
// beside the exhaustive loops whose answers it must give bit for bit.
//
//   std::vector<Bounds> boxes;  for (const Primitive& p : scene.objects)
//   boxes.push_back(WorldBound(p)); const Bvh bvh = BuildBvh(boxes, pad);   // nodes[0] is the
//   root; order[] the objects in leaf order
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "hosts/scene/geometry.h"
#include "hosts/scene/scene.h"

namespace zephyr {

// An axis-aligned box in world units; empty (lo > hi) when default-made.
struct Bounds {
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity()};
  void Grow(const Vec3& p);
  void Grow(const Bounds& b);
  bool Empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  // xy + yz + zx of the extents, world units² (0 when empty): the SAH's weight.
  double HalfArea() const;
  Vec3 Centre() const { return (lo + hi) * 0.5; }
};

// A box holding every point of the primitive in world space, in double, before any
// padding: a sphere centre ± r; an ellipsoid (a transformed sphere) its exact box,
// r·‖row i of A‖₂ about the mapped centre; a cone the union of its two end discs' boxes
// (radius |r|: the open truncated cone lies in their convex hull); a transformed cone the
// eight corners of that box mapped; a polygon (or patch) its vertices, mapped. Rounding of
// these few operations is left to the caller's padding.
Bounds WorldBound(const Primitive& p);

// One node of the hierarchy, boxes stored in the tracer's scalar T. A leaf (count > 0)
// holds order[first .. first + count); an inner node (count == 0) has its two children at
// nodes[first] and nodes[first + 1], side by side so one visit reads both boxes.
template <typename T>
struct BvhNodeT {
  T lo[3], hi[3];
  int32_t first = 0;
  int32_t count = 0;
};

// The deepest a BvhNode may lie below the root (the build makes a leaf there): bounds a
// traversal's stack (kBvhMaxDepth + 2 entries).
inline constexpr int kBvhMaxDepth = 60;

struct Bvh {
  std::vector<BvhNodeT<double>> nodes;  // nodes[0]: the root (absent for no objects)
  std::vector<int32_t> order;           // object indices, leaf after leaf
  int depth = 0;                        // the deepest node's depth (root 0)
  // The build's counted work (TraceStats, docs/shading.md "The BVH"): primitives binned
  // (one object's centroid placed in a bin and its box grown, on the axes where the node's
  // centroids spread; a node whose centroids coincide bins nothing), and nodes made (each
  // with its SAH sweep over the bins).
  uint64_t binnedPrimitives = 0;
  uint64_t nodesBuilt = 0;
};

// Bins per axis of the SAH build, the most objects in one leaf, and the SAH's cost of one
// node visit (its two child boxes) relative to one primitive test (assumed: 2, about two
// sphere tests; with leaves of up to 8 the fastest of 1, 2, 3 and 4 on bench_trace's 4096
// spheres, pbrt-v4 and Wald's binned builder use 1 with smaller leaves).
inline constexpr int kBvhBins = 16;
inline constexpr int kBvhMaxLeaf = 8;
inline constexpr double kBvhTraversalCost = 2.0;

// The binned-SAH hierarchy over `boxes` (one per object, Scene::objects order; none may be
// empty: ZEPHYR_CHECK, a caller's bug), each node's box grown by `pad` world units on every
// side (>= 0, checked likewise). Leaves hold at
// most kBvhMaxLeaf objects unless their centroids coincide or kBvhMaxDepth is reached. The
// same boxes give the same hierarchy on every machine (no threads, no hashing).
Bvh BuildBvh(const std::vector<Bounds>& boxes, double pad);

}  // namespace zephyr
