// hosts/methods/report.h — the render report (`render --report FILE`): the one place its
// schema and key style (lowerCamel) live. A render keeps its results typed (RenderOutput,
// hosts/methods/render.h) and this writes them once, at the edge. The sections also printed
// by other commands keep their serializer beside their type: the cycle report
// (bitserial::CycleReport::Json, `zephyr cycles`), the plan (simd::PrimaryPlan::Json,
// `zephyr plan`), the farm's figures (FarmReport::Json, `zephyr mpi-check`), the counted work
// (TraceStats::ToJson, the children's stats messages) and the modelled time
// (testbed::ModelledTime::Json). The keys: docs/report.md.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include "hosts/methods/output.h"
#include "hosts/simd/pass.h"

namespace zephyr {

// The whole report of a finished render.
nlohmann::json RenderReportJson(const RenderOutput& out);

// The SIMD pass's section ("simd"): plan, cycles (every array pass), uncertain pixels,
// the refine pass, timings. `zephyr accuracy` writes the same per method.
nlohmann::json PrimaryPassJson(const simd::PrimaryPass& pass);

// One run of the array program's cycles: the summed cycle report with memory and timing,
// and, for several array passes, each pass's under "passes".
nlohmann::json ArrayRunJson(const simd::ArrayRunReport& run);

}  // namespace zephyr
