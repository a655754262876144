// hosts/scene/pov.h — export a scene to POV-Ray 3.7 SDL, mapping our shading model onto
// POV-Ray's (docs/shading.md), so POV-Ray can serve as an independent reference image.
#pragma once

#include <string>

#include "hosts/scene/scene.h"

namespace zephyr {

// depth: our --depth (POV-Ray's max_trace_level counts the same way: primary rays are 1).
std::string ExportPov(const Scene& scene, int depth);

// The povray command line that renders `pov` to `png` as docs/background.md, "Outside reference
// points", gives it (headless, no anti-aliasing, linear output).
std::string PovrayCommand(const std::string& pov, const std::string& png, int width, int height);

}  // namespace zephyr
