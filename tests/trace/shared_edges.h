// tests/trace/shared_edges.h — pairs of faces sharing one edge, for the shared-edge rule of
// the host tracer (tests/trace/edges_test.cpp) and of the SIMD pass (tests/simd/edges_test.cpp):
// a ray through the edge meets exactly one of the two faces (docs/shading.md, "Polygons";
// docs/simd.md, "Polygons").
//
// The edges: ends differing only in x, only in y, only in z, and in all three (a diagonal);
// each lies in a plane through the eye that a line of pixel centres also lies in exactly (the
// middle row, the middle column, the main diagonal), so those pixels' rays pass exactly
// through it and their edge functions are exactly 0. The faces: quads (convex) or notched
// pentagons (concave; fanned from the notch, so the fan's triangles tile it, or from an end of
// the edge, so they overlap and the parity decides), folded into a ridge or a valley or flat,
// wound consistently or not. Each face is a scene of its own, so that a ray meeting both (a
// double hit) is seen as well as one meeting neither (a crack).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "hosts/scene/scene.h"
#include "hosts/trace/tracer.h"

namespace zephyr::testing {

struct SharedEdgeCase {
  std::string name;  // "x edge, concave (fan from the notch), ridge, consistent winding"
  Scene a, b;        // each face alone, the same camera (65×65, the eye at the origin)
  Vec3 edgeFrom, edgeTo;
  std::vector<int> line;  // pixels whose rays pass exactly through the edge, 5 % from its ends
  std::vector<int> band;  // pixels whose rays pass within 2.5 pixels of the edge, 5 % from its ends
  // Concave faces fanned from the notch: points of face a's fan diagonals (the edges its fan
  // triangles share inside it), 5 % from their ends; a ray through one meets face a once.
  std::vector<Vec3> diagonalPoints;
};

inline std::vector<SharedEdgeCase> SharedEdgeCases() {
  struct Edge {
    const char* name;
    Vec3 from, to, at;  // the edge's ends and where the camera looks
    int lineKind;       // 0: the middle row, 1: the middle column, 2: the diagonal x = y
  };
  const Edge edges[] = {
      {"x edge", {-1.3, 0, -5}, {1.7, 0, -5}, {0, 0, -1}, 0},
      {"y edge", {0, -1.1, -5}, {0, 1.6, -5}, {0, 0, -1}, 1},
      {"z edge", {-5, 0, -1.2}, {-5, 0, 1.5}, {-1, 0, 0}, 0},
      {"diagonal edge", {-1, 1, -4}, {1.5, -1.5, -6}, {0, 0, -1}, 2},
  };
  const char* shapes[] = {"convex quad", "concave (fan from the notch)",
                          "concave (fan from an end)"};
  const char* folds[] = {"ridge", "valley", "flat"};
  constexpr int kSize = 65;
  std::vector<SharedEdgeCase> cases;
  for (const Edge& edge : edges) {
    const Vec3 a = edge.from, b = edge.to, e = Normalize(b - a);
    const Vec3 foot = a - e * Dot(a, e);  // the edge line's point nearest the eye
    const Vec3 away = Normalize(foot), side = Normalize(Cross(a, b));  // in and across its plane
    for (int shape = 0; shape < 3; ++shape)
      for (int fold = 0; fold < 3; ++fold)
        for (const bool consistent : {true, false}) {
          SharedEdgeCase c;
          c.name = std::string(edge.name) + ", " + shapes[shape] + ", " + folds[fold] + ", " +
                   (consistent ? "consistent" : "inconsistent") + " winding";
          c.edgeFrom = a, c.edgeTo = b;
          const double tilt = fold == 0 ? 0.5 : fold == 1 ? -0.5 : 0;
          // Face a spreads across the edge's plane toward +side, face b toward −side.
          auto face = [&](double sign, bool reversed) {
            const Vec3 u = Normalize(side * sign + away * tilt) * 1.5;
            const Vec3 notch = (a + b) * 0.5 + u * 0.4;
            std::vector<Vec3> v;
            if (shape == 0) v = {a, b, b + u, a + u};
            if (shape == 1) v = {notch, a + u, a, b, b + u};
            if (shape == 2) v = {a, b, b + u, notch, a + u};
            if (reversed) std::reverse(v.begin() + 1, v.end());  // vertex 0 (the fan's centre) kept
            if (shape == 1 && sign > 0)
              for (const Vec3& end : {a, b})
                for (int k = 1; k < 20; ++k)
                  c.diagonalPoints.push_back(notch + (end - notch) * (k / 20.0));
            return v;
          };
          for (const bool isA : {true, false}) {
            Scene& s = isA ? c.a : c.b;
            s.source = c.name;
            s.camera = Camera{{0, 0, 0}, edge.at, {0, 1, 0}, 40, 0.01, kSize, kSize};
            s.materials = {Material{{1, 1, 1}, 1, 0, 0, 0, 1}};
            Primitive p;
            // Consistent: the faces run along the shared edge in opposite directions.
            p.shape = Polygon{face(isA ? 1 : -1, isA ? false : consistent), {}};
            s.objects.push_back(p);
          }
          const PrimaryRays rays(c.a.camera);
          const double pitch = 2 * std::tan(20 * M_PI / 180) / (kSize - 1);
          for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
              // Where the pixel's ray passes the edge's line: s along the edge, and how far.
              const Vec3 d = rays.At(x, y).direction, w = b - a;
              const double dw = Dot(d, w), ww = Dot(w, w), ad = Dot(a, d), aw = Dot(a, w);
              const double s = (ad * dw - aw) / (ww - dw * dw);
              const Vec3 q = a + w * s;
              const double miss = Length(q - d * Dot(q, d)) / Length(q);  // radians
              if (s < 0.05 || s > 0.95) continue;
              const bool onLine = edge.lineKind == 0   ? y == kSize / 2
                                  : edge.lineKind == 1 ? x == kSize / 2
                                                       : x == y;
              if (onLine) c.line.push_back(y * kSize + x);
              if (miss < 2.5 * pitch) c.band.push_back(y * kSize + x);
            }
          cases.push_back(c);
        }
  }
  return cases;
}

}  // namespace zephyr::testing
