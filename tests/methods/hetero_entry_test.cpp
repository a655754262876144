// hetero's compact matrix entry (hosts/methods/hetero_entry.h): what the parent puts is what the
// child gets, the recomputed direction is the SIMD pass's own, and malformed entries are rejected.
#include "hosts/methods/hetero_entry.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "fixed/check.h"
#include "hosts/simd/pass.h"

namespace zephyr {
namespace {

Scene SmallScene() {
  Scene s;
  s.camera.from = {0, 0, -10};
  s.camera.at = {0, 0, 0};
  s.camera.up = {0, 1, 0};
  s.camera.angleDegrees = 30;
  s.materials.push_back(Material{});
  s.camera.width = 24, s.camera.height = 16;
  Primitive p;
  p.shape = Sphere{{0, 0, 0}, 2};
  s.objects.push_back(p);
  p.shape = Sphere{{1.5, 0.5, -1}, 0.7};
  s.objects.push_back(p);
  return s;
}

TEST(HeteroEntry, RoundTripsObjectTAndFlags) {
  std::byte bytes[hetero::kEntryBytes];
  PrimaryHit hit;
  hit.object = 7, hit.t = 12.345678901234567;
  hetero::PutEntry(hit, simd::kGrazing | simd::kRecomputed, bytes);
  std::uint32_t flags = 0;
  const PrimaryHit back = hetero::GetEntry(bytes, 8, flags);
  EXPECT_EQ(back.object, 7);
  EXPECT_EQ(std::memcmp(&back.t, &hit.t, sizeof(double)), 0);
  EXPECT_EQ(flags, simd::kGrazing | simd::kRecomputed);
}

TEST(HeteroEntry, RejectsMalformedEntries) {
  std::byte bytes[hetero::kEntryBytes];
  std::uint32_t flags = 0;
  PrimaryHit hit;
  hit.object = 8, hit.t = 1;  // a scene of 8 objects has 0..7
  hetero::PutEntry(hit, 0, bytes);
  EXPECT_THROW(hetero::GetEntry(bytes, 8, flags), UserError);
  hit.object = -2;
  hetero::PutEntry(hit, 0, bytes);
  EXPECT_THROW(hetero::GetEntry(bytes, 8, flags), UserError);
  hit.object = 3, hit.t = std::numeric_limits<double>::quiet_NaN();
  hetero::PutEntry(hit, 0, bytes);
  EXPECT_THROW(hetero::GetEntry(bytes, 8, flags), UserError);
  hit.object = -1, hit.t = 2;  // a miss carries t = 0
  hetero::PutEntry(hit, 0, bytes);
  EXPECT_THROW(hetero::GetEntry(bytes, 8, flags), UserError);
  hit.object = 3, hit.t = 2;
  hetero::PutEntry(hit, 0x80, bytes);  // not a simd::PixelFlag
  EXPECT_THROW(hetero::GetEntry(bytes, 8, flags), UserError);
  hetero::PutEntry(hit, simd::kNearTie, bytes);
  EXPECT_NO_THROW(hetero::GetEntry(bytes, 8, flags));
}

TEST(HeteroEntry, RecomputedDirectionIsTheMatrixDirectionBitForBit) {
  const Scene scene = SmallScene();
  const PrimaryRays rays(scene.camera);
  for (const auto policy : {simd::UncertainPolicy::kKeep, simd::UncertainPolicy::kRecompute,
                            simd::UncertainPolicy::kRefine}) {
    for (int dirBits : {6, 20}) {  // coarse directions make grazing pixels, recomputed or not
      simd::SimdOptions options;
      options.uncertain = policy;
      options.formats.dirFracBits = dirBits;
      const simd::PrimaryPass pass = simd::RunPrimaryPass(scene, options);
      // As the parent's set-up message names them (hosts/methods/hetero.cpp).
      const int refineBits = pass.refine ? pass.refine->dirFracBits : -1;
      int mismatches = 0, recomputed = 0, refined = 0;
      for (int y = 0; y < scene.camera.height; ++y)
        for (int x = 0; x < scene.camera.width; ++x) {
          const std::size_t i = std::size_t(y) * scene.camera.width + x;
          const Vec3 d = hetero::MatrixDirection(rays, x, y, pass.plan.dirFracBits, refineBits,
                                                 pass.matrix.flags[i]);
          mismatches += std::memcmp(&d, &pass.matrix.hits[i].direction, sizeof(Vec3)) != 0;
          recomputed += (pass.matrix.flags[i] & simd::kRecomputed) != 0;
          refined += (pass.matrix.flags[i] & simd::kRefined) != 0;
        }
      EXPECT_EQ(mismatches, 0) << "dirFracBits " << dirBits;
      if (policy == simd::UncertainPolicy::kKeep) {
        EXPECT_EQ(recomputed, 0);
      } else if (dirBits == 6) {
        EXPECT_GT(recomputed + refined, 0) << "6-bit directions should leave uncertain pixels";
      }
      if (policy == simd::UncertainPolicy::kRefine) {
        EXPECT_GT(refined, 0) << "the refine pass should certify some pixels";
        // A refined pixel's direction is the refine pass's: without its bits it cannot be had.
        for (std::size_t i = 0; i < pass.matrix.flags.size(); ++i)
          if (pass.matrix.flags[i] & simd::kRefined) {
            EXPECT_THROW(hetero::MatrixDirection(rays, 0, 0, pass.plan.dirFracBits, -1,
                                                 pass.matrix.flags[i]),
                         UserError);
            break;
          }
      } else {
        EXPECT_EQ(refined, 0);
      }
    }
  }
}

}  // namespace
}  // namespace zephyr
