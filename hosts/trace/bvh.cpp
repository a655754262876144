#include "hosts/trace/bvh.h"

#include <algorithm>
#include <cmath>
#include <variant>

#include "fixed/check.h"

namespace zephyr {

void Bounds::Grow(const Vec3& p) {
  lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
  hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
}

void Bounds::Grow(const Bounds& b) {
  if (b.Empty()) return;
  Grow(b.lo);
  Grow(b.hi);
}

double Bounds::HalfArea() const {
  if (Empty()) return 0;
  const Vec3 e = hi - lo;
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

namespace {

// The box of a disc of radius r about c whose unit normal is u: r·sqrt(1 − u_i²) on axis i.
Bounds DiscBound(const Vec3& c, const Vec3& u, double r) {
  r = std::abs(r);
  const Vec3 e{r * std::sqrt(std::max(0.0, 1 - u.x * u.x)),
               r * std::sqrt(std::max(0.0, 1 - u.y * u.y)),
               r * std::sqrt(std::max(0.0, 1 - u.z * u.z))};
  Bounds b;
  b.Grow(c - e);
  b.Grow(c + e);
  return b;
}

Bounds ConeBound(const Cone& c) {
  const Vec3 u = Normalize(c.apex - c.base);
  Bounds b = DiscBound(c.base, u, c.baseRadius);
  b.Grow(DiscBound(c.apex, u, c.apexRadius));
  return b;
}

}  // namespace

Bounds WorldBound(const Primitive& p) {
  Bounds b;
  if (const auto* poly = std::get_if<Polygon>(&p.shape)) {
    for (const Vec3& v : poly->vertices) b.Grow(p.transform ? p.transform->ApplyPoint(v) : v);
  } else if (const auto* s = std::get_if<Sphere>(&p.shape)) {
    if (!p.transform) {
      const Vec3 r{s->radius, s->radius, s->radius};
      b.Grow(s->centre - r);
      b.Grow(s->centre + r);
    } else {
      // The ellipsoid {A x + t : |x − c| <= r}: on axis i, A c + t ± r·‖row i of A‖₂.
      const Affine& a = *p.transform;
      const Vec3 centre = a.ApplyPoint(s->centre);
      double e[3];
      for (int i = 0; i < 3; ++i)
        e[i] = std::abs(s->radius) *
               std::sqrt(a.m[i][0] * a.m[i][0] + a.m[i][1] * a.m[i][1] + a.m[i][2] * a.m[i][2]);
      b.Grow(centre - Vec3{e[0], e[1], e[2]});
      b.Grow(centre + Vec3{e[0], e[1], e[2]});
    }
  } else {
    const Bounds object = ConeBound(std::get<Cone>(p.shape));
    if (!p.transform) return object;
    for (int corner = 0; corner < 8; ++corner)
      b.Grow(p.transform->ApplyPoint({corner & 1 ? object.hi.x : object.lo.x,
                                      corner & 2 ? object.hi.y : object.lo.y,
                                      corner & 4 ? object.hi.z : object.lo.z}));
  }
  return b;
}

namespace {

struct Builder {
  const std::vector<Bounds>& boxes;
  double pad;
  std::vector<Vec3> centres;
  Bvh bvh;

  // Makes nodes[index] over order[begin, end) at `depth`, then its children.
  void Build(int32_t index, int32_t begin, int32_t end, int depth) {
    ++bvh.nodesBuilt;
    bvh.depth = std::max(bvh.depth, depth);
    Bounds box, centroidBox;
    for (int32_t k = begin; k < end; ++k) {
      box.Grow(boxes[bvh.order[k]]);
      centroidBox.Grow(centres[bvh.order[k]]);
    }
    BvhNodeT<double>& node = bvh.nodes[index];
    for (int i = 0; i < 3; ++i) {
      node.lo[i] = box.lo[i] - pad;
      node.hi[i] = box.hi[i] + pad;
    }
    const int32_t count = end - begin;
    int axis = -1, splitBin = 0;
    double bestCost = std::numeric_limits<double>::infinity();
    if (count > 1 && depth < kBvhMaxDepth) {
      bool binned = false;
      for (int a = 0; a < 3; ++a) {
        const double lo = centroidBox.lo[a], extent = centroidBox.hi[a] - lo;
        if (!(extent > 0)) continue;
        if (!binned) bvh.binnedPrimitives += uint64_t(count);  // once, however many axes
        binned = true;
        Bounds binBox[kBvhBins];
        int binCount[kBvhBins] = {};
        for (int32_t k = begin; k < end; ++k) {
          const int bin = BinOf(centres[bvh.order[k]][a], lo, extent);
          ++binCount[bin];
          binBox[bin].Grow(boxes[bvh.order[k]]);
        }
        // Sweep: the cost of splitting after bin s, left boxes from the left, right from the right.
        double rightArea[kBvhBins];
        int rightCount[kBvhBins];
        Bounds acc;
        int n = 0;
        for (int s = kBvhBins - 1; s > 0; --s) {
          acc.Grow(binBox[s]);
          n += binCount[s];
          rightArea[s] = acc.HalfArea();
          rightCount[s] = n;
        }
        acc = Bounds();
        n = 0;
        for (int s = 0; s + 1 < kBvhBins; ++s) {
          acc.Grow(binBox[s]);
          n += binCount[s];
          if (n == 0 || rightCount[s + 1] == 0) continue;
          const double cost = acc.HalfArea() * n + rightArea[s + 1] * rightCount[s + 1];
          if (cost < bestCost) {
            bestCost = cost;
            axis = a;
            splitBin = s;
          }
        }
      }
    }
    // The SAH: a leaf costs its tests; a split one visit plus its children's expected tests.
    const double area = box.HalfArea();
    const bool split =
        axis >= 0 &&
        (count > kBvhMaxLeaf || (area > 0 && kBvhTraversalCost + bestCost / area < double(count)));
    if (!split) {
      node.first = begin;
      node.count = count;
      return;
    }
    const double lo = centroidBox.lo[axis], extent = centroidBox.hi[axis] - lo;
    const auto mid = std::stable_partition(
        bvh.order.begin() + begin, bvh.order.begin() + end,
        [&](int32_t i) { return BinOf(centres[i][axis], lo, extent) <= splitBin; });
    const int32_t middle = int32_t(mid - bvh.order.begin());
    ZEPHYR_CHECK(middle > begin && middle < end);
    const int32_t children = int32_t(bvh.nodes.size());
    bvh.nodes.emplace_back();
    bvh.nodes.emplace_back();
    bvh.nodes[index].first = children;  // (the reference above may have moved)
    bvh.nodes[index].count = 0;
    Build(children, begin, middle, depth + 1);
    Build(children + 1, middle, end, depth + 1);
  }

  static int BinOf(double c, double lo, double extent) {
    const int bin = int(double(kBvhBins) * ((c - lo) / extent));
    return std::clamp(bin, 0, kBvhBins - 1);
  }
};

}  // namespace

Bvh BuildBvh(const std::vector<Bounds>& boxes, double pad) {
  ZEPHYR_CHECK(pad >= 0);
  Builder b{boxes, pad, {}, {}};
  if (boxes.empty()) return b.bvh;
  for (size_t i = 0; i < boxes.size(); ++i) {
    ZEPHYR_CHECK(!boxes[i].Empty());
    b.centres.push_back(boxes[i].Centre());
    b.bvh.order.push_back(int32_t(i));
  }
  b.bvh.nodes.reserve(2 * boxes.size());
  b.bvh.nodes.emplace_back();
  b.Build(0, 0, int32_t(boxes.size()), 0);
  return b.bvh;
}

}  // namespace zephyr
