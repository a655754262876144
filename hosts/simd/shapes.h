// hosts/simd/shapes.h — the per-primitive programs of the SIMD primary pass and their error
// analysis (docs/simd.md, "The program" and "Error bounds"). Internal to hosts/simd*.
//
// Every primitive is reduced on the host to `uni` constants (the eye and T⁻¹ folded in) and
// tested on the array against the multi direction d (s1.Fd, the double unit direction
// rounded to nearest). For each object the host first derives, from the formats, sound
// bounds on the error of every quantity (ObjectBounds); the array program then gives per
// PE a candidate t, whether it is a hit, and whether the decision is uncertain (within the
// bounds of a boundary: grazing, the rim of a polygon, hither) together with a lower bound
// on where the true hit could be.
#pragma once

#include <string>
#include <vector>

#include "bitserial/multi.h"
#include "hosts/scene/scene.h"

namespace zephyr::simd {

// The pass-wide formats the shapes share.
struct PassFormats {
  int fracBits = 0;     // F: fraction bits of every length, product and t
  int dirFracBits = 0;  // Fd: fraction bits of the direction components
  fixed::Format t;      // t (and the distances it is built from)
  double hither = 0;    // max(camera hither, 0)
  double Ulp() const;        // 2^-F: a floor-rounded result's error
  double DirError() const;   // 2^-Fd / 2: a direction component's rounding error
};

// What the host knows about one object before the pass (world-space eye).
struct ObjectBounds {
  ShapeKind kind = ShapeKind::kSphere;
  bool transformed = false;
  double farthest = 0;     // farthest point of the object from the eye
  double tError = 0;       // |t − t_exact| for a hit that is not flagged
  double slack = 0;        // a flagged candidate's true t is >= its computed t − slack
  double grazeBand = 0;    // |discriminant| (or |edge function|) below this is grazing
  int intBits = 1;         // widest integer part among the object's quantities
  bool alwaysUncertain = false;  // bounds degenerate at these widths: every candidate flagged
};

ObjectBounds BoundObject(const Scene& scene, int index, const PassFormats& formats);

// One object's answer on the array (all multis over every PE).
struct Candidate {
  bitserial::Multi t;          // in formats.t; meaningful where hit or uncertain
  bitserial::Multi hit;        // 1 bit: a hit beyond hither at t
  bitserial::Multi uncertain;  // 1 bit: the hit/miss or hither decision is within the bounds
  bitserial::Multi tLow;       // in formats.t: where uncertain, the true hit (if any) is >= tLow
};

// Runs the array program of object `index` (every primitive kind runs on the array) against
// the directions.
Candidate TestObject(bitserial::Machine& m, const Scene& scene, int index,
                     const bitserial::Multi (&d)[3], const PassFormats& formats,
                     const ObjectBounds& bounds);

}  // namespace zephyr::simd
