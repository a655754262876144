// The SIMD pass's uncertain-pixel flags against their rules (docs/simd.md, "Error bounds" and
// "Uncertain pixels"), on cases whose discriminant and t gap are known exactly in double:
//  * grazing: a sphere is grazing at a pixel when its computed discriminant is within the
//    band G of zero. The computed value is within e_disc of the exact D, and e_disc <=
//    (e_t − u)·√G (e_t = e_tca + e_disc/√G + u), G itself is rounded to F bits: so |D| below
//    G − e_disc − u must be flagged and |D| above G + e_disc + u must not (G >= 2·e_disc also
//    bounds e_disc by G/2). Each case puts one
//    pixel just inside or just outside the band, at three fraction widths and three radii;
//  * near tie: hits of spheres j and k are tied when t_j − e_j <= t_k + e_k (each e_i = e_t of
//    its sphere + u, rounded to F bits). The computed t of each sphere is read from a run of
//    that sphere alone (same formats: it does not depend on the other objects), so the rule
//    is decided exactly for every pixel both hit with certainty; the gaps straddle e_j + e_k
//    and e_j alone.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hosts/simd/pass.h"
#include "hosts/simd/plan.h"

namespace zephyr::simd {
namespace {

constexpr int kSize = 33;

Scene SphereScene(const std::vector<Sphere>& spheres) {
  Scene s;
  s.source = "uncertain test";
  s.camera = Camera{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 30, 0, kSize, kSize};
  s.lights = {Light{{5, 5, 5}, {1, 1, 1}}};
  s.materials = {Material{}};
  for (const Sphere& sp : spheres) {
    Primitive p;
    p.shape = sp;
    s.objects.push_back(p);
  }
  return s;
}

SimdOptions Keep(int fracBits) {
  SimdOptions o;
  o.formats.fracBits = fracBits;
  o.formats.intBits = 6;  // the same t format whatever the objects
  o.uncertain = UncertainPolicy::kKeep;
  return o;
}

// Object `index`'s bounds as the pass uses them.
ObjectBounds Bounds(const Scene& scene, int index, const SimdOptions& o) {
  return PlanPrimaryPass(scene, o).objects[index].bounds;
}

// |f × d̂|² for the ray of pixel (x, y): the exact discriminant is r² minus this.
double CrossSquared(const Scene& s, const Vec3& centre, int x, int y) {
  const PrimaryRay ray = PrimaryRays(s.camera).At(x, y);
  const Vec3 f = centre - ray.origin;
  return Dot(f, f) - Dot(f, ray.direction) * Dot(f, ray.direction);
}

TEST(SimdUncertain, GrazingFlagFollowsTheBandOnBothSides) {
  const Vec3 centre = PrimaryRays(SphereScene({}).camera).At(16, 16).direction * 10.0;
  int cases = 0, totalIn = 0, totalOut = 0;
  for (int fracBits : {10, 16, 20})
    for (int row : {13, 10, 4}) {  // target pixel (16, row): radii about 0.5, 1 and 2
      const double c2 = CrossSquared(SphereScene({}), centre, 16, row);
      // side: the target's D relative to the band: just inside (±) and just outside (±).
      for (double side : {-1.0, 1.0})
        for (bool inside : {true, false}) {
          Scene scene = SphereScene({Sphere{centre, std::sqrt(c2)}});
          const SimdOptions o = Keep(fracBits);
          double g = 0, margin = 0;
          for (int it = 0; it < 3; ++it) {  // the band depends (weakly) on the radius
            const ObjectBounds b = Bounds(scene, 0, o);
            const double u = std::ldexp(1.0, -fracBits);
            g = b.grazeBand;
            margin = std::min((b.tError - u) * std::sqrt(g), g / 2) + u;
            const double d = side * (inside ? (g - margin) * 0.98 : (g + margin) * 1.02);
            std::get<Sphere>(scene.objects[0].shape).radius = std::sqrt(c2 + d);
          }
          const ObjectBounds b = Bounds(scene, 0, o);  // the final radius's band and margin
          const double u = std::ldexp(1.0, -fracBits);
          g = b.grazeBand;
          margin = std::min((b.tError - u) * std::sqrt(g), g / 2) + u;
          ASSERT_LT(margin, g) << "F " << fracBits;
          if (fracBits >= 16) {  // wide enough that half the band is decided on both sides
            ASSERT_LT(margin, g / 4) << "F " << fracBits;
          }
          const double r = std::get<Sphere>(scene.objects[0].shape).radius;
          const PrimaryPass pass = RunPrimaryPass(scene, o);
          const std::string what = "F " + std::to_string(fracBits) + " r " + std::to_string(r) +
                                   " G " + std::to_string(g) + (inside ? " inside" : " outside");
          int in = 0, out = 0;
          for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
              const double d = r * r - CrossSquared(scene, centre, x, y);
              const bool flagged = pass.matrix.flags[size_t(y) * kSize + x] & kGrazing;
              if (std::abs(d) <= g - margin) {
                ++in;
                EXPECT_TRUE(flagged) << what << ": pixel " << x << "," << y << " D " << d;
              } else if (std::abs(d) >= g + margin) {
                ++out;
                EXPECT_FALSE(flagged) << what << ": pixel " << x << "," << y << " D " << d;
              }
              if (x == 16 && y == row) {  // the target pixel is in the class it was put in
                EXPECT_EQ(std::abs(d) <= g - margin, inside) << what << " D " << d;
                EXPECT_EQ(std::abs(d) >= g + margin, !inside) << what << " D " << d;
                EXPECT_EQ(d > 0, side > 0) << what;
              }
            }
          EXPECT_GT(inside ? in : out, 0) << what;  // at least the target pixel
          totalIn += in, totalOut += out;
          ++cases;
        }
    }
  EXPECT_EQ(cases, 36);
  EXPECT_GT(totalIn, 36);
  EXPECT_GT(totalOut, 36);
}

TEST(SimdUncertain, NearTieFlagFollowsThePairRule) {
  int tiedPixels = 0, apartPixels = 0, onlyBothBounds = 0, exactlyAtTheLimit = 0;
  for (int fracBits : {11, 15}) {
    const SimdOptions o = Keep(fracBits);
    const double u = std::ldexp(1.0, -fracBits);
    const Vec3 axis = PrimaryRays(SphereScene({}).camera).At(16, 16).direction;
    // Front sphere k: radius 1 at distance 10 (t_k = 9 on the axis); sphere j, radius 0.5,
    // behind it on the same axis with t_j = 9 + gap on the axis.
    const Sphere k{axis * 10.0, 1};
    const ObjectBounds bk = Bounds(SphereScene({k}), 0, o);
    const ObjectBounds bj0 = Bounds(SphereScene({Sphere{axis * 9.5, 0.5}}), 0, o);
    const double both = bk.tError + bj0.tError + 2 * u;
    // The gaps: apart, tied, and a few F-bit steps around the limit itself, where a pair
    // exactly e_k + e_j apart is a near tie (the rule is <=, docs/simd.md).
    std::vector<double> shares = {0.2, 0.6, 0.9, 1.1, 1.6, 3.0};
    for (int step = -3; step <= 3; ++step) shares.push_back(1.0 + step * u / both);
    for (double share : shares) {
      const Sphere j{axis * (9.5 + share * both), 0.5};
      const auto run = [&](const std::vector<Sphere>& s) {
        return RunPrimaryPass(SphereScene(s), o);
      };
      const PrimaryPass alone[2] = {run({k}), run({j})}, pair = run({k, j});
      const ObjectBounds b[2] = {bk, Bounds(SphereScene({j}), 0, o)};
      double e[2];  // e_i + u rounded to F bits, as the pass loads it
      for (int i = 0; i < 2; ++i)
        e[i] = std::ldexp(std::nearbyint(std::ldexp(b[i].tError + u, fracBits)), -fracBits);
      int decided = 0;
      for (size_t p = 0; p < pair.matrix.flags.size(); ++p) {
        if (alone[0].matrix.hits[p].object != 0 || alone[1].matrix.hits[p].object != 0 ||
            alone[0].matrix.flags[p] || alone[1].matrix.flags[p] ||
            (pair.matrix.flags[p] & kGrazing))
          continue;
        const double tk = alone[0].matrix.hits[p].t, tj = alone[1].matrix.hits[p].t;
        const bool tied = std::abs(tj - tk) <= e[0] + e[1];
        exactlyAtTheLimit += std::abs(tj - tk) == e[0] + e[1];
        const std::string what = "F " + std::to_string(fracBits) + " gap share " +
                                 std::to_string(share) + " pixel " + std::to_string(p) + " t " +
                                 std::to_string(tk) + " " + std::to_string(tj) + " e " +
                                 std::to_string(e[0]) + " " + std::to_string(e[1]);
        EXPECT_EQ(bool(pair.matrix.flags[p] & kNearTie), tied) << what;
        // The first object is the nearer computed t (ties to the lower index).
        EXPECT_EQ(pair.matrix.hits[p].object, tj < tk ? 1 : 0) << what;
        ++decided;
        tied ? ++tiedPixels : ++apartPixels;
        onlyBothBounds += tied && std::abs(tj - tk) > std::max(e[0], e[1]);
      }
      EXPECT_GT(decided, 20) << "F " << fracBits << " share " << share;
    }
  }
  EXPECT_GT(tiedPixels, 0);
  EXPECT_GT(apartPixels, 0);
  EXPECT_GT(exactlyAtTheLimit, 0) << "no pair exactly at the limit: the <= of the rule is untested";
  EXPECT_GT(onlyBothBounds, 0);  // gaps that only the sum e_j + e_k covers, not one bound
}

}  // namespace
}  // namespace zephyr::simd

namespace zephyr::simd {
namespace {

// A polygon's t bound divides by the least n̂·d a ray reaching it can have, less that
// denominator's own error eE (the grazing band): with the plane at distance n from the eye and
// its farthest vertex at R, a polygon seen so edge-on that n/R <= eE has every hit flagged,
// and otherwise tError >= R·eE / (n/R − eE) (docs/simd.md, "Error bounds").
TEST(SimdUncertain, ANearlyEdgeOnPolygonsBoundCountsItsDenominatorsError) {
  const SimdOptions o = Keep(12);
  auto floorAt = [](double n) {
    Scene s = SphereScene({});
    Polygon p;
    p.vertices = {{-1, -n, -2}, {1, -n, -2}, {1, -n, -4}, {-1, -n, -4}};
    Primitive prim;
    prim.shape = p;
    s.objects.push_back(prim);
    return s;
  };
  const double eE = Bounds(floorAt(1), 0, o).grazeBand;
  ASSERT_GT(eE, 0);
  int flagged = 0, bounded = 0;
  for (double k : {0.25, 0.5, 0.9, 1.2, 2.0, 8.0}) {
    const double n = k * eE * std::sqrt(17.0);
    const ObjectBounds b = Bounds(floorAt(n), 0, o);
    const double ratio = n / b.farthest;
    if (ratio <= eE) {
      EXPECT_TRUE(b.alwaysUncertain) << "n/R = " << ratio / eE << " eE";
      ++flagged;
    } else if (!b.alwaysUncertain) {
      EXPECT_GE(b.tError, b.farthest * eE / (ratio - eE)) << "n/R = " << ratio / eE << " eE";
      ++bounded;
    }
  }
  EXPECT_GT(flagged, 0);
  EXPECT_GT(bounded, 0);
}

}  // namespace
}  // namespace zephyr::simd
