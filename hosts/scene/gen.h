// hosts/scene/gen.h — deterministic scene generators (our own code, so tests and `make run` need
// nothing outside the repository). Same seed, same scene, on every platform: the random
// numbers come from SplitMix64, not from <random>'s distributions.
#pragma once

#include <cstdint>

#include "hosts/scene/scene.h"

namespace zephyr {

// The generators' limits (gen spheres --count, gen flake --depth): a million spheres is
// past what an exhaustive tracer renders; depth 6 is 597,871 spheres.
inline constexpr int kMaxRandomSpheres = 1000000;
inline constexpr int kMaxFlakeDepth = 6;

struct RandomSpheresOptions {
  int count = 32;
  uint64_t seed = 1;
  int width = 384, height = 384;  // the paper's image size (§6)
};

// The paper's test scene: `count` non-overlapping spheres at random in front of the eye, a
// mix of diffuse (60 %), mirror (20 %) and glass (20 %) materials, inside a region that
// covers the middle of the view, so background shows around them and corner frames are
// empty.
Scene GenerateRandomSpheres(const RandomSpheresOptions& options);

// A sphereflake like SPD `balls`: a sphere with nine children a third its size, recursively
// to `depth` levels (depth 0 = one sphere), on a floor polygon, with SPD's view and lights.
Scene GenerateSphereflake(int depth, int width = 512, int height = 512);

// A small scene exercising the transform extension: an ellipsoid, a sheared cylinder, a
// rotated cone and a transformed cube (six polygons) on a floor.
Scene GenerateTransformedShowcase(int width = 384, int height = 384);

}  // namespace zephyr
