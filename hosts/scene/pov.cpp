// hosts/scene/pov.cpp — our scene as POV-Ray 3.7 SDL (`zephyr export-pov` is
// hosts/cmd/export_pov.cpp).
#include "hosts/scene/pov.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <variant>
#include <vector>

#include "fixed/check.h"
#include "hosts/scene/nff.h"

namespace zephyr {

namespace {

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
std::string Vec(const Vec3& v) { return "<" + Num(v.x) + ", " + Num(v.y) + ", " + Num(v.z) + ">"; }

// POV-Ray weights a surface's own lighting (diffuse and highlight) by its opacity
// 1 − transmit, where ours uses Kd and Ks as given; the exporter divides them back out.
// Reflection and transmission are not weighted, in either renderer.
// The ambient term (docs/shading.md: A · Kd · C) is POV-Ray's finish ambient Kd against
// ambient_light A, divided by the opacity like the diffuse weight.
// withInterior false: the interior goes on the union that holds the object (ExportPov).
std::string Texture(const Material& m, bool withInterior) {
  const double opacity = 1 - m.t;
  const double scale = opacity > 1e-6 ? 1 / opacity : 0;
  std::string s = "  pigment { rgb " + Vec(m.colour);
  if (m.t > 0) s += " transmit " + Num(m.t);
  s += " }\n  finish { ambient " + Num(m.kd * scale) + " emission 0 diffuse " + Num(m.kd * scale);
  if (m.ks > 0) {
    s += " phong " + Num(m.ks * scale) + " phong_size " + Num(m.shine);
    s += " reflection { " + Num(m.ks) + " }";
  }
  s += " }\n";
  if (m.t > 0 && withInterior) s += "  interior { ior " + Num(m.ior) + " }\n";
  return s;
}

std::string Matrix(const Affine& a) {
  // POV-Ray's matrix lists the columns of the linear part, then the translation.
  std::string s = "  matrix <";
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) s += Num(a.m[r][c]) + ((c == 3 && r == 2) ? ">\n" : ", ");
  return s;
}

}  // namespace

std::string ExportPov(const Scene& scene, int depth) {
  const Camera& c = scene.camera;
  std::string out = "// Exported by `zephyr export-pov` from " + scene.source + "\n";
  const double ambient = scene.Ambient();
  out += "#version 3.7;\nglobal_settings { assumed_gamma 1.0 max_trace_level " +
         std::to_string(depth) + " adc_bailout 0 ambient_light " +
         Vec(Vec3{ambient, ambient, ambient}) + " }\n";
  out += "background { rgb " + Vec(scene.background) + " }\n";
  // Our camera (hosts/trace/tracer.cpp PrimaryRays): `angle` spans the centres of the top and
  // bottom rows. POV-Ray's image plane spans the pixel edges, so up and right are the
  // pixel pitch times the pixel counts. Explicit vectors keep our right-handed frame.
  const Vec3 forward = Normalize(ScaledDown(c.at - c.from));
  const Vec3 right = Normalize(ScaledDown(Cross(forward, ScaledDown(c.up))));
  const Vec3 up = Cross(right, forward);
  const double pitch = 2 * std::tan(c.angleDegrees * M_PI / 360) / std::max(c.height - 1, 1);
  out += "camera { perspective location " + Vec(c.from) + " direction " + Vec(forward) + " right " +
         Vec(right * (pitch * c.width)) + " up " + Vec(up * (pitch * c.height)) + " }\n";
  // Lights with the intensity every method shades with (SPD's √N/(2N) when a light has no colour).
  for (size_t i = 0; i < scene.lights.size(); ++i)
    out += "light_source { " + Vec(scene.lights[i].position) + " color rgb " +
           Vec(scene.LightColour(i)) + " }\n";
  // Ours refracts by the side of the surface a ray meets (docs/shading.md: entering against
  // the normal, leaving along it); POV-Ray by the interiors the ray has entered: a ray meeting
  // an object whose interior it is not in enters it, with the ratio of that ior to the one it
  // is in. A polygon has no inside of its own, so a glass solid made of polygons (SPD gears:
  // two 144-gons and 144 quads) exported polygon by polygon would have as many interiors as
  // faces: a ray would bend entering the first face and pass every later face straight
  // (1.1/1.1). The transmissive polygons of one material therefore share one interior, that
  // of one union around them: leaving through any face leaves it, as the outward normals of a
  // closed solid say in our tracer. Disjoint solids of one material may share it (each is
  // entered and left in turn).
  std::vector<int> unionOrder;             // materials with transmissive polygons, first seen first
  std::map<int, std::string> unionBodies;  // material -> the polygons of its union
  for (const Primitive& o : scene.objects) {
    std::string body;
    if (auto* s = std::get_if<Sphere>(&o.shape)) {
      body = "sphere { " + Vec(s->centre) + ", " + Num(s->radius) + "\n";
    } else if (auto* cn = std::get_if<Cone>(&o.shape)) {
      if (cn->baseRadius == cn->apexRadius)
        body = "cylinder { " + Vec(cn->base) + ", " + Vec(cn->apex) + ", " + Num(cn->baseRadius) +
               " open\n";
      else
        body = "cone { " + Vec(cn->base) + ", " + Num(cn->baseRadius) + ", " + Vec(cn->apex) +
               ", " + Num(cn->apexRadius) + " open\n";
    } else {
      const auto& p = std::get<Polygon>(o.shape);
      if (p.normals.empty()) {
        body = "polygon { " + std::to_string(p.vertices.size() + 1);
        for (const Vec3& v : p.vertices) body += ", " + Vec(v);
        body += ", " + Vec(p.vertices[0]) + "\n";
      } else {
        body = "mesh {\n";  // a fan of smooth triangles, as our tracer interpolates
        for (size_t i = 1; i + 1 < p.vertices.size(); ++i)
          body += "  smooth_triangle { " + Vec(p.vertices[0]) + ", " + Vec(p.normals[0]) + ", " +
                  Vec(p.vertices[i]) + ", " + Vec(p.normals[i]) + ", " + Vec(p.vertices[i + 1]) +
                  ", " + Vec(p.normals[i + 1]) + " }\n";
      }
    }
    const Material& m = scene.materials.at(o.material);
    const bool joined = m.t > 0 && std::holds_alternative<Polygon>(o.shape);
    body += Texture(m, !joined);
    if (o.transform) body += Matrix(*o.transform);
    body += "}\n";
    if (!joined) {
      out += body;
      continue;
    }
    if (unionBodies.find(o.material) == unionBodies.end()) unionOrder.push_back(o.material);
    unionBodies[o.material] += body;
  }
  for (const int material : unionOrder)
    out += "union {\n" + unionBodies[material] + "  interior { ior " +
           Num(scene.materials[material].ior) + " }\n}\n";
  return out;
}

std::string PovrayCommand(const std::string& pov, const std::string& png, int width, int height) {
  return "povray -D +I'" + pov + "' +O'" + png + "' +FN +W" + std::to_string(width) + " +H" +
         std::to_string(height) + " -A File_Gamma=1.0 Output_Alpha=off";
}

}  // namespace zephyr
