// The vector nearest-sphere kernel against the scalar loop it replaces, on every compiled
// Highway target: same object, same bits of t (sphere_kernels.h contract).
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "hosts/trace/sphere_kernels.h"
#include "hosts/trace/tracer.h"

namespace zephyr {
namespace {

template <typename T>
uint64_t Bits(T v) {
  if constexpr (sizeof(T) == 4)
    return std::bit_cast<uint32_t>(v);
  else
    return std::bit_cast<uint64_t>(v);
}

template <typename T>
struct Case {
  SphereArrays<T> spheres;
  Vec3T<T> o, d;
  T tMin;
};

// A random unit vector.
Vec3 RandomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const Vec3 v{g(rng), g(rng), g(rng)};
    if (Length(v) > 1e-3) return Normalize(v);
  }
}

// Spheres of every kind the tracer meets: plain hits and misses, grazing ones (centre at
// radius distance from the ray line), ones holding the origin, exact duplicates (equal t
// at different indices, across lanes and in the remainder) and ones behind the origin.
template <typename T>
Case<T> RandomCase(std::mt19937_64& rng, size_t n) {
  std::uniform_real_distribution<double> u(-1, 1), pos(0, 1);
  Case<T> c;
  const Vec3 o{10 * u(rng), 10 * u(rng), 10 * u(rng)};
  const Vec3 d = RandomUnit(rng);
  c.o = Vec3T<T>(o);
  c.d = Vec3T<T>(d);
  c.tMin = pos(rng) < 0.3 ? T(0) : T(0.5 * pos(rng));
  for (size_t i = 0; i < n; ++i) {
    const double kind = pos(rng);
    const double r = 0.05 + 2 * pos(rng);
    Vec3 centre;
    if (kind < 0.25) {  // somewhere along the ray, near its line
      centre = o + d * (30 * pos(rng)) + RandomUnit(rng) * (r * 1.5 * pos(rng));
    } else if (kind < 0.45) {  // grazing: centre at distance r from the line
      Vec3 side = Cross(d, RandomUnit(rng));
      side = Normalize(side);
      centre = o + d * (40 * u(rng)) + side * r;
    } else if (kind < 0.55) {  // holding the origin
      centre = o + RandomUnit(rng) * (0.9 * r * pos(rng));
    } else if (kind < 0.7 && i > 0) {  // a duplicate of an earlier sphere
      const size_t j = size_t(pos(rng) * double(i)) % i;
      c.spheres.Push({c.spheres.cx[j], c.spheres.cy[j], c.spheres.cz[j]}, c.spheres.r2[j]);
      continue;
    } else {  // anywhere (mostly misses, some behind the origin)
      centre = Vec3{20 * u(rng), 20 * u(rng), 20 * u(rng)};
    }
    c.spheres.Push(Vec3T<T>(centre), T(r * r));
  }
  return c;
}

// Runs `body` once per target compiled in and supported here; returns how many.
template <typename F>
int ForEachTarget(F&& body) {
  int count = 0;
  for (const uint32_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    body(hwy::TargetName(target));
    ++count;
  }
  hwy::SetSupportedTargetsForTest(0);
  return count;
}

template <typename T>
void CheckRandomCases(SphereTest form) {
  int hits = 0, misses = 0, ties = 0;
  const int targets = ForEachTarget([&](const char* name) {
    std::mt19937_64 rng(12345);  // the same cases on every target
    for (int k = 0; k < 1500; ++k) {
      const Case<T> c = RandomCase<T>(rng, size_t(k % 41));
      T tScalar, tVector;
      const int32_t scalar = NearestSphereScalar(form, c.spheres, c.o, c.d, c.tMin, &tScalar);
      const int32_t vector = NearestSphere(form, c.spheres, c.o, c.d, c.tMin, &tVector);
      ASSERT_EQ(vector, scalar) << name << " case " << k;
      ASSERT_EQ(Bits(tVector), Bits(tScalar))
          << name << " case " << k << ": " << tVector << " vs " << tScalar;
      (scalar >= 0 ? hits : misses)++;
      // A later exact duplicate of the winner: the scalar loop keeps the lower index.
      if (scalar >= 0) {
        for (size_t j = size_t(scalar) + 1; j < c.spheres.Size(); ++j) {
          if (c.spheres.cx[j] == c.spheres.cx[scalar] && c.spheres.cy[j] == c.spheres.cy[scalar] &&
              c.spheres.cz[j] == c.spheres.cz[scalar] && c.spheres.r2[j] == c.spheres.r2[scalar])
            ++ties;
        }
      }
    }
  });
  EXPECT_GE(targets, 1);
  // The cases exercised what they claim to.
  EXPECT_GT(hits, 100 * targets);
  EXPECT_GT(misses, 100 * targets);
  EXPECT_GT(ties, 10 * targets);
}

TEST(TraceKernels, HearnBakerFloatMatchesScalarOnEveryTarget) {
  CheckRandomCases<float>(SphereTest::kHearnBaker);
}
TEST(TraceKernels, HearnBakerDoubleMatchesScalarOnEveryTarget) {
  CheckRandomCases<double>(SphereTest::kHearnBaker);
}
TEST(TraceKernels, NaiveFloatMatchesScalarOnEveryTarget) {
  CheckRandomCases<float>(SphereTest::kNaive);
}
TEST(TraceKernels, NaiveDoubleMatchesScalarOnEveryTarget) {
  CheckRandomCases<double>(SphereTest::kNaive);
}

// Hand-made edge cases: the ray touching a sphere at its own origin (q = 0: a miss in the
// Hearn–Baker form), the origin inside (the far root), the near root below tMin, equal t
// across the lanes and in the remainder, and no spheres at all.
TEST(TraceKernels, EdgeCasesOnEveryTarget) {
  for (const SphereTest form : {SphereTest::kHearnBaker, SphereTest::kNaive}) {
    ForEachTarget([&](const char* name) {
      const Vec3T<double> o{0, 0, 0}, d{1, 0, 0};
      double t;
      SphereArrays<double> none;
      EXPECT_EQ(NearestSphere(form, none, o, d, 0.0, &t), -1);
      EXPECT_EQ(t, INFINITY);

      SphereArrays<double> touch;  // tangent at the origin
      touch.Push({0, 1, 0}, 1);
      double tScalar;
      EXPECT_EQ(NearestSphere(form, touch, o, d, 0.0, &t),
                NearestSphereScalar(form, touch, o, d, 0.0, &tScalar));
      EXPECT_EQ(Bits(t), Bits(tScalar));
      if (form == SphereTest::kHearnBaker) {
        EXPECT_EQ(NearestSphere(form, touch, o, d, 0.0, &t), -1);
      }

      SphereArrays<double> s;
      s.Push({0, 0, 0}, 4);                               // 0: holds the origin: far root t = 2
      s.Push({10, 0, 0}, 1);                              // 1: t = 9
      s.Push({10, 0, 0}, 1);                              // 2: the same, higher index
      for (int i = 0; i < 17; ++i) s.Push({5, 3, 0}, 1);  // misses, pushes 19 and 20 into any tail
      s.Push({1.5, 0, 0}, 1);                             // 20: t = 0.5 (near root) or 2.5
      s.Push({1.5, 0, 0}, 1);                             // 21
      EXPECT_EQ(NearestSphere(form, s, o, d, 0.0, &t), 20) << name;
      EXPECT_EQ(t, 0.5);
      EXPECT_EQ(NearestSphere(form, s, o, d, 0.6, &t), 0) << name;  // 2 < 2.5
      EXPECT_EQ(t, 2.0);
      EXPECT_EQ(NearestSphere(form, s, o, d, 2.6, &t), 1) << name;  // tie 1 vs 2
      EXPECT_EQ(t, 9.0);
      EXPECT_EQ(NearestSphere(form, s, o, d, 11.0, &t), -1) << name;
    });
  }
}

// The tracer's nearest-hit search (kernel for plain spheres, scalar for the rest) gives the
// same primary hits on every target: seq is bit-reproducible whatever the machine picks.
TEST(TraceKernels, TracerFirstHitsIdenticalOnEveryTarget) {
  Scene scene;
  scene.camera.from = {0, 0, -10};
  scene.camera.at = {0, 0, 0};
  scene.camera.up = {0, 1, 0};
  scene.camera.angleDegrees = 40;
  scene.camera.width = scene.camera.height = 24;
  scene.materials.push_back(Material{});
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int i = 0; i < 23; ++i) {
    Primitive p;
    p.shape = Sphere{{u(rng), u(rng), u(rng)}, 0.3 + std::abs(u(rng)) / 4};
    p.material = 0;
    scene.objects.push_back(p);
    if (i % 5 == 0) scene.objects.push_back(p);  // an exact duplicate: equal t
    if (i == 11) {                               // a polygon among them, on the scalar path
      Primitive wall;
      wall.shape = Polygon{{{-2, -2, 1}, {2, -2, 1}, {2, 2, 1}, {-2, 2, 1}}, {}};
      scene.objects.push_back(wall);
    }
  }
  for (const Precision precision : {Precision::kFloat, Precision::kDouble}) {
    for (const SphereTest form : {SphereTest::kHearnBaker, SphereTest::kNaive}) {
      TraceOptions options;
      options.precision = precision;
      options.sphereTest = form;
      std::vector<std::vector<PrimaryHit>> perTarget;
      ForEachTarget([&](const char*) {
        const auto tracer = Tracer::Create(scene, options);
        std::vector<Vec3> image;
        TraceStats stats;
        perTarget.emplace_back();
        RenderRegion(*tracer, 0, 0, 24, 24, image, stats, &perTarget.back());
      });
      int hits = 0;
      for (const PrimaryHit& h : perTarget[0]) hits += h.object >= 0;
      EXPECT_GT(hits, 24);
      if (precision == Precision::kDouble) {  // the plain scan over every object, in order
        const PrimaryRays rays(scene.camera);
        for (int i = 0; i < 24 * 24; ++i) {
          const PrimaryRay r = rays.At(i % 24, i / 24);
          int best = -1;
          double tBest = INFINITY;
          for (size_t k = 0; k < scene.objects.size(); ++k) {
            const auto t = IntersectObject(scene, int(k), r.origin, r.direction, 0, form);
            if (t && *t < tBest) {
              tBest = *t;
              best = int(k);
            }
          }
          ASSERT_EQ(perTarget[0][i].object, best) << "pixel " << i;
          if (best >= 0) {
            ASSERT_EQ(Bits(perTarget[0][i].t), Bits(tBest)) << "pixel " << i;
          }
        }
      }
      for (size_t k = 1; k < perTarget.size(); ++k) {
        for (size_t i = 0; i < perTarget[0].size(); ++i) {
          ASSERT_EQ(perTarget[k][i].object, perTarget[0][i].object) << k << " pixel " << i;
          ASSERT_EQ(Bits(perTarget[k][i].t), Bits(perTarget[0][i].t)) << k << " pixel " << i;
        }
      }
    }
  }
}

}  // namespace
}  // namespace zephyr
