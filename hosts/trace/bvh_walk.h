// hosts/trace/bvh_walk.h — the host tracer's hierarchy as its rays walk it (--accel bvh;
// docs/shading.md, "The BVH"): built beside the tracer's prepared objects from BuildBvh's
// nodes (hosts/trace/bvh.h), each box rounded outward to the tracer's scalar, and one walk
// with two leaf visitors — the nearest hit (nearer child first, a box entered beyond the best
// t skipped) and the light let through to a light (every box the segment meets, the
// crossings multiplied in object order). Both give exactly what the exhaustive loops give,
// with their counted work (node visits, box tests, tests by kind) added to TraceStats.
//
//   BvhWalkT<double> walk(scene, objects, SphereTest::kHearnBaker);
//   if (walk.Answers(o)) object = walk.Nearest(o, d, tMin, stats, t);
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "hosts/scene/scene.h"
#include "hosts/trace/bvh.h"
#include "hosts/trace/intersect.h"
#include "hosts/trace/prepared.h"
#include "hosts/trace/tracer.h"

namespace zephyr {

template <typename T>
class BvhWalkT {
  using V = Vec3T<T>;

 public:
  // The hierarchy over `objects` (the scene's objects prepared, Scene::objects order; kept
  // by reference, so they must outlive the walk and not move), their tests in sphere form
  // `form`. A scene without objects has none: Answers is false.
  BvhWalkT(const Scene& scene, const std::vector<Prepared<T>>& objects, SphereTest form)
      : objects_(&objects), form_(form) {
    Build(scene, objects);
  }

  // Whether the walk answers for rays from o: a hierarchy was built and o lies within the
  // reach its padding covers (Build); other rays take the exhaustive loops.
  bool Answers(const V& o) const { return built_ && MaxAbs(o) <= originLimit_; }
  // The build's counted work (TraceStats::bvhBinned, bvhNodes).
  uint64_t Binned() const { return binned_; }
  uint64_t NodesBuilt() const { return nodesBuilt_; }

  // The nearest object along o + t d with its first root in (tMin, inf) (−1: none), its t
  // in tBest: nearer child first; a box is skipped only when it is entered strictly beyond
  // the best t (one entered at t may hold a lower index at t). Ties go to the lower index
  // as in the exhaustive loop, whatever the visiting order.
  int Nearest(const V& o, const V& d, T tMin, TraceStats& stats, T& tBest) const {
    NearestVisitor nearest;
    Walk(o, d, tMin, nearest, stats);
    tBest = nearest.tBest;
    return nearest.best;
  }

  // The light let through along the segment (tMin, dist) from p toward a light: every box
  // the segment meets, the crossings (object, roots nearer than dist) collected and
  // multiplied in object order, as the exhaustive loop multiplies them (floating-point
  // products depend on the order). An opaque surface crossed makes the product 0 at once
  // (the exhaustive product is 0 too). Child 1 is visited before child 0 (as a stack pushed
  // 0 then 1 would pop them).
  T Transmission(const V& p, const V& toLight, T dist, T tMin, TraceStats& stats) const {
    thread_local std::vector<Crossing> crossed;
    crossed.clear();
    TransmissionVisitor through{dist, &crossed};
    Walk(p, toLight, tMin, through, stats);
    if (through.opaque) return T(0);
    std::sort(crossed.begin(), crossed.end(),
              [](const Crossing& a, const Crossing& b) { return a.object < b.object; });
    T product = T(1);
    for (const Crossing& c : crossed)
      for (int i = 0; i < c.count; ++i) {
        product *= c.transparency;
        if (product == T(0)) return product;
      }
    return product;
  }

 private:
  // Exactness rests on two things. (1) The objects are tested by the very functions the
  // exhaustive loops call (the leaf's untransformed sphere by IntersectSphere, which the
  // vector kernel matches bit for bit; the rest by Intersect), so a tested object gives the
  // same roots. (2) No object with a root that counts is culled: each box is grown by a pad
  // far above the rounding of both the object's test and the slab test, so any root an
  // object's test returns lies inside the (padded) box's computed slab interval. Both round
  // with the magnitudes of the ray's origin and the scene (|o|, |x| <= reach): the pad is
  // kBvhPadRelative·reach (2⁻²⁴ in double, 2⁻¹² in float: ~10⁸ and ~4000 ulps of reach), a
  // transformed object's box grown further by its map's condition number (its test rounds in
  // object space), and a ray whose origin lies beyond reach (which no hit point or light
  // does) takes the exhaustive loop.
  static constexpr double kBvhPadRelative = std::is_same_v<T, float> ? 0x1p-12 : 0x1p-24;

  struct LeafObject {  // one entry of order[], with an untransformed sphere's data inline
    V centre;
    T radius2 = 0;
    int32_t object = 0;
    bool sphere = false;  // an untransformed sphere: IntersectSphere on centre, radius2
    ShapeKind kind = ShapeKind::kSphere;
    T transparency = 0;  // its material's T, as Transmission multiplies by it
  };

  // What the walk keeps of a node: a leaf's objects leaves_[first, first + count), or an
  // inner node's index in inner_ (count 0). Trivial (no initialisers), so a walk's stack of
  // them costs nothing to declare.
  struct NodeRef {
    int32_t first, count;
  };

  // An inner node as the walk reads it: its two children's boxes by axis then child (one
  // SIMD lane a child) and what each child is. One record per inner node, nothing else
  // between them, aligned to whole cache lines: 112 bytes padded to 128 in double (two
  // 64-byte lines, the pair the L2's adjacent-line prefetch fetches together), 64 in float.
  struct alignas(64) Inner {
    T lo[3][2], hi[3][2];
    NodeRef child[2];
  };

  static T RoundDown(double v) {
    T f = T(v);
    if (double(f) > v) f = std::nextafter(f, -std::numeric_limits<T>::infinity());
    return f;
  }
  static T RoundUp(double v) {
    T f = T(v);
    if (double(f) < v) f = std::nextafter(f, std::numeric_limits<T>::infinity());
    return f;
  }

  void Build(const Scene& scene, const std::vector<Prepared<T>>& objects) {
    if (scene.objects.empty()) return;
    std::vector<Bounds> boxes;
    boxes.reserve(scene.objects.size());
    double reach = MaxAbs(scene.camera.from);
    for (const Light& l : scene.lights) reach = std::max(reach, MaxAbs(l.position));
    for (const Primitive& p : scene.objects) {
      boxes.push_back(WorldBound(p));
      reach = std::max({reach, MaxAbs(boxes.back().lo), MaxAbs(boxes.back().hi)});
    }
    // Hit points lie within the boxes (up to rounding), so twice the reach holds every
    // origin a secondary or shadow ray has.
    originLimit_ = T(2 * reach);
    const double pad = kBvhPadRelative * 2 * reach + double(std::numeric_limits<T>::min());
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const Primitive& p = scene.objects[i];
      if (!p.transform || p.Kind() == ShapeKind::kPolygon) continue;  // polygons: world space
      const double condition =
          p.transform->LinearNormInf() * p.transform->Inverse().LinearNormInf();
      const double grow = kBvhPadRelative * condition * 2 * reach;
      boxes[i].lo = boxes[i].lo - Vec3{grow, grow, grow};
      boxes[i].hi = boxes[i].hi + Vec3{grow, grow, grow};
    }
    const Bvh bvh = BuildBvh(boxes, pad);
    // Each node's box in T, rounded outward.
    std::vector<BvhNodeT<T>> nodes;
    nodes.reserve(bvh.nodes.size());
    for (const BvhNodeT<double>& n : bvh.nodes) {
      BvhNodeT<T> m;
      for (int a = 0; a < 3; ++a) {
        m.lo[a] = RoundDown(n.lo[a]);
        m.hi[a] = RoundUp(n.hi[a]);
      }
      m.first = n.first;
      m.count = n.count;
      nodes.push_back(m);
    }
    // The inner nodes numbered densely in the build's order (a node's near descendants
    // stay near it in memory).
    std::vector<int32_t> innerIndex(nodes.size(), -1);
    int32_t inner = 0;
    for (size_t i = 0; i < nodes.size(); ++i)
      if (nodes[i].count == 0) innerIndex[i] = inner++;
    auto reference = [&](int32_t node) {
      return nodes[node].count > 0 ? NodeRef{nodes[node].first, nodes[node].count}
                                   : NodeRef{innerIndex[node], 0};
    };
    rootBox_ = nodes[0];
    root_ = reference(0);
    // Each inner node's two child boxes side by side, for EntersPair, with what each child
    // is: the walk reads nothing else of a node.
    inner_.resize(size_t(inner));
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (nodes[i].count > 0) continue;
      Inner& record = inner_[size_t(innerIndex[i])];
      for (int c = 0; c < 2; ++c) {
        const int32_t child = nodes[i].first + c;
        for (int a = 0; a < 3; ++a) {
          record.lo[a][c] = nodes[child].lo[a];
          record.hi[a][c] = nodes[child].hi[a];
        }
        record.child[c] = reference(child);
      }
    }
    for (const int32_t i : bvh.order) {
      const Prepared<T>& obj = objects[i];
      LeafObject leaf;
      leaf.object = i;
      leaf.kind = obj.kind;
      leaf.sphere = obj.kind == ShapeKind::kSphere && !obj.transformed;
      leaf.centre = obj.centre;
      leaf.radius2 = obj.radius2;
      leaf.transparency = T(scene.materials[obj.material].t);
      leaves_.push_back(leaf);
    }
    built_ = true;
    binned_ = bvh.binnedPrimitives;
    nodesBuilt_ = bvh.nodesBuilt;
  }

#if defined(__SSE2__)
  static constexpr bool kPairSse2 = std::is_same_v<T, double>;
#else
  static constexpr bool kPairSse2 = false;
#endif

  // A ray's set-up for slab tests, made once per ray: its origin and the reciprocals of its
  // direction (±inf for a zero component), and with SSE2 in double each broadcast to both
  // lanes, so a visit loads only the node's boxes.
  struct SlabRay {
    T o[3], inv[3];
#if defined(__SSE2__)
    __m128d vo[3], vinv[3];
#endif
    SlabRay(const V& origin, const V& d)
        : o{origin.x, origin.y, origin.z}, inv{T(1) / d.x, T(1) / d.y, T(1) / d.z} {
#if defined(__SSE2__)
      if constexpr (kPairSse2)
        for (int a = 0; a < 3; ++a) {
          vo[a] = _mm_set1_pd(o[a]);
          vinv[a] = _mm_set1_pd(inv[a]);
        }
#endif
    }
  };

  // Whether the ray's slab interval [tNear, tFar] through box n meets [tMin, tMax]; tNear
  // in *near. A NaN (0·inf: the origin on a box plane along a zero component) constrains
  // nothing on that axis, or culls a ray lying in a padded face, which no object reaches.
  static bool Enters(const BvhNodeT<T>& n, const SlabRay& r, T tMin, T tMax, T* near) {
    T lo = -std::numeric_limits<T>::infinity(), hi = std::numeric_limits<T>::infinity();
    for (int a = 0; a < 3; ++a) {
      const T t0 = (n.lo[a] - r.o[a]) * r.inv[a], t1 = (n.hi[a] - r.o[a]) * r.inv[a];
      const T tn = t0 < t1 ? t0 : t1, tf = t0 < t1 ? t1 : t0;
      if (tn > lo) lo = tn;
      if (tf < hi) hi = tf;
    }
    *near = lo;
    return lo <= hi && hi >= tMin && lo <= tMax;
  }

  // Enters for both children of an inner node at once: bit c of the result set when child c
  // is entered, its tNear in near[c]. With SSE2 (double) two lanes; otherwise the same
  // operations lane by lane (min(a, b) = a < b ? a : b and max(a, b) = a > b ? a : b, as
  // minpd and maxpd), so the same boxes are entered on every machine. NaN: as in Enters.
  static inline __attribute__((always_inline)) int EntersPair(const Inner& b, const SlabRay& r,
                                                              T tMin, T tMax, T near[2]) {
#if defined(__SSE2__)
    if constexpr (kPairSse2) {
      // The three axes written out (the compiler keeps the loop at -O2).
      const __m128d a0 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.lo[0]), r.vo[0]), r.vinv[0]);
      const __m128d b0 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.hi[0]), r.vo[0]), r.vinv[0]);
      const __m128d a1 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.lo[1]), r.vo[1]), r.vinv[1]);
      const __m128d b1 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.hi[1]), r.vo[1]), r.vinv[1]);
      const __m128d a2 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.lo[2]), r.vo[2]), r.vinv[2]);
      const __m128d b2 = _mm_mul_pd(_mm_sub_pd(_mm_load_pd(b.hi[2]), r.vo[2]), r.vinv[2]);
      __m128d lo = _mm_set1_pd(-std::numeric_limits<double>::infinity());
      __m128d hi = _mm_set1_pd(std::numeric_limits<double>::infinity());
      lo = _mm_max_pd(_mm_min_pd(a0, b0), lo);
      hi = _mm_min_pd(_mm_max_pd(a0, b0), hi);
      lo = _mm_max_pd(_mm_min_pd(a1, b1), lo);
      hi = _mm_min_pd(_mm_max_pd(a1, b1), hi);
      lo = _mm_max_pd(_mm_min_pd(a2, b2), lo);
      hi = _mm_min_pd(_mm_max_pd(a2, b2), hi);
      _mm_storeu_pd(near, lo);
      const __m128d ok =
          _mm_and_pd(_mm_and_pd(_mm_cmple_pd(lo, hi), _mm_cmpge_pd(hi, _mm_set1_pd(tMin))),
                     _mm_cmple_pd(lo, _mm_set1_pd(tMax)));
      return _mm_movemask_pd(ok);
    }
#endif
    int mask = 0;
    for (int c = 0; c < 2; ++c) {
      T lo = -std::numeric_limits<T>::infinity(), hi = std::numeric_limits<T>::infinity();
      for (int a = 0; a < 3; ++a) {
        const T t0 = (b.lo[a][c] - r.o[a]) * r.inv[a], t1 = (b.hi[a][c] - r.o[a]) * r.inv[a];
        const T tn = t0 < t1 ? t0 : t1, tf = t0 > t1 ? t0 : t1;
        lo = tn > lo ? tn : lo;
        hi = tf < hi ? tf : hi;
      }
      near[c] = lo;
      if (lo <= hi && hi >= tMin && lo <= tMax) mask |= 1 << c;
    }
    return mask;
  }

  // One leaf object's roots along the ray, as the exhaustive loops compute them; counted in
  // tests[kind] (the walk's own counters, added to TraceStats at its end).
  inline __attribute__((always_inline)) int TestLeaf(const LeafObject& leaf, const V& o, const V& d,
                                                     T tMin, T* roots, uint64_t* tests) const {
    ++tests[int(leaf.kind)];
    if (leaf.sphere)  // IntersectSphere's two forms called by name, so both are inlined
      return form_ == SphereTest::kHearnBaker
                 ? IntersectSphereHearnBaker(o, d, leaf.centre, leaf.radius2, tMin, roots)
                 : IntersectSphereNaive(o, d, leaf.centre, leaf.radius2, tMin, roots);
    return Intersect((*objects_)[leaf.object], form_, o, d, tMin, roots);
  }

  // The walk's counts, kept in locals (not behind the TraceStats reference, which the
  // compiler must assume aliases the walk's own state) and added once per ray.
  struct WalkCounts {
    uint64_t boxTests = 0, visits = 0, tests[kShapeKinds] = {};
    void AddTo(TraceStats& stats) const {
      stats.boxTests += boxTests;
      stats.nodeVisits += visits;
      for (int k = 0; k < kShapeKinds; ++k) stats.tests[k] += tests[k];
    }
  };

  struct StackEntry {  // trivial, like NodeRef
    NodeRef node;
    T tNear;
  };


  // The walk both visitors share. A visitor gives Limit() (the far end of the boxes worth
  // entering: the best t so far, or the light's distance), kNearerFirst (visit the nearer
  // of two entered children first and skip a stacked box entered beyond Limit(); otherwise
  // child 1 first, every entered box visited) and Object(leaf, found, roots), false to stop
  // the walk. The nearer (or only) child entered is visited at once rather than pushed and
  // popped: it was entered at or before Limit(), which nothing has changed since, so the
  // pop's test would pass it (the same visits in the same order).
  template <class Visitor>
  void Walk(const V& o, const V& d, T tMin, Visitor& visitor, TraceStats& stats) const {
    const SlabRay ray(o, d);
    T near;
    ++stats.boxTests;
    if (!Enters(rootBox_, ray, tMin, visitor.Limit(), &near)) return;
    StackEntry stack[kBvhMaxDepth + 2];
    int top = 0;
    NodeRef n = root_;
    T roots[2];
    WalkCounts counts;
    for (;;) {
      ++counts.visits;
      if (n.count > 0) {
        for (int32_t k = n.first; k < n.first + n.count; ++k) {
          const LeafObject& leaf = leaves_[k];
          const int found = TestLeaf(leaf, o, d, tMin, roots, counts.tests);
          if (!visitor.Object(leaf, found, roots)) {
            counts.AddTo(stats);
            return;
          }
        }
      } else {
        T nearChild[2];
        counts.boxTests += 2;
        const Inner& node = inner_[n.first];
        const int entered = EntersPair(node, ray, tMin, visitor.Limit(), nearChild);
        // Which child comes next is chosen by branches, not by an index computed from the
        // test: a predicted branch lets the next node's loads start before this node's test
        // has finished (an index would make every visit wait for the last one's test).
        if (entered == 3) {
          if (Visitor::kNearerFirst && nearChild[0] <= nearChild[1]) {  // the nearer first
            stack[top++] = {node.child[1], nearChild[1]};
            n = node.child[0];
          } else {
            stack[top++] = {node.child[0], nearChild[0]};
            n = node.child[1];
          }
          continue;
        }
        if (entered == 1) {
          n = node.child[0];
          continue;
        }
        if (entered == 2) {
          n = node.child[1];
          continue;
        }
      }
      // The next entry (an ordered walk: not entered beyond the limit).
      if constexpr (Visitor::kNearerFirst)
        while (top > 0 && stack[top - 1].tNear > visitor.Limit()) --top;
      if (top == 0) break;
      n = stack[--top].node;
    }
    counts.AddTo(stats);
  }

  struct NearestVisitor {
    static constexpr bool kNearerFirst = true;
    T tBest = std::numeric_limits<T>::infinity();
    int best = -1;
    T Limit() const { return tBest; }
    bool Object(const LeafObject& leaf, int found, const T* roots) {
      if (found > 0 && (roots[0] < tBest || (roots[0] == tBest && leaf.object < best))) {
        tBest = roots[0];
        best = leaf.object;
      }
      return true;
    }
  };

  struct Crossing {
    int32_t object, count;
    T transparency;
  };
  struct TransmissionVisitor {
    static constexpr bool kNearerFirst = false;
    T dist;
    std::vector<Crossing>* crossed;
    bool opaque = false;
    T Limit() const { return dist; }
    bool Object(const LeafObject& leaf, int found, const T* roots) {
      int count = 0;
      for (int i = 0; i < found; ++i) {
        if (roots[i] >= dist) break;
        ++count;
      }
      if (count == 0) return true;
      if (leaf.transparency == T(0)) {
        opaque = true;
        return false;
      }
      crossed->push_back({leaf.object, count, leaf.transparency});
      return true;
    }
  };

  const std::vector<Prepared<T>>* objects_;
  SphereTest form_;
  // The hierarchy (built_ false: none), its objects in leaf order, the largest |coordinate|
  // of an origin it answers for (Build), and the build's counted work.
  bool built_ = false;
  BvhNodeT<T> rootBox_;
  NodeRef root_{0, 0};
  std::vector<Inner> inner_;  // the inner nodes' records (Inner)
  std::vector<LeafObject> leaves_;
  T originLimit_ = 0;
  uint64_t binned_ = 0, nodesBuilt_ = 0;
};

}  // namespace zephyr
