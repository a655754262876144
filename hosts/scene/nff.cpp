#include "hosts/scene/nff.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "fixed/check.h"
#include "fixed/input_file.h"

namespace zephyr {

namespace {

struct Token {
  std::string_view text;
  int line = 0, column = 0;
};

// Splits NFF text into whitespace-separated tokens, dropping `#` comments, one token at a
// time (a file of 33 million tokens is never held as a list). SPD writes a cone on one line
// or two, so the grammar works on the token stream, not on lines. A line ends at LF, CRLF
// or a lone CR (classic Mac files), so comments and line numbers are right in all three; a
// leading UTF-8 byte-order mark is skipped.
class TokenStream {
 public:
  explicit TokenStream(std::string_view text) : text_(text) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") i_ = 3;
  }
  bool AtEnd() { return !Fill(); }
  // The next token, or the last one read when the text is used up (where "missing ..."
  // errors point inside a statement).
  const Token& Peek() { return Fill() ? next_ : last_; }
  Token Take() {
    Fill();
    has_ = false;
    last_ = next_;
    return last_;
  }
  // Just past the last byte, for "unexpected end of file" errors (valid once AtEnd()).
  int EndLine() const { return line_; }
  int EndColumn() const { return column_; }

 private:
  bool LineEnd(size_t at) const { return text_[at] == '\n' || text_[at] == '\r'; }
  bool IsSpace(size_t at) const {
    const char c = text_[at];
    return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == '\n' || c == '\r';
  }
  bool Fill() {
    if (has_) return true;
    while (i_ < text_.size()) {
      const char c = text_[i_];
      if (LineEnd(i_)) {
        if (c == '\r' && i_ + 1 < text_.size() && text_[i_ + 1] == '\n') ++i_;  // CRLF is one end
        ++line_;
        column_ = 1;
        ++i_;
      } else if (IsSpace(i_)) {
        ++column_;
        ++i_;
      } else if (c == '#') {
        while (i_ < text_.size() && !LineEnd(i_)) ++i_, ++column_;
      } else {
        const size_t start = i_;
        const int startColumn = column_;
        while (i_ < text_.size() && !IsSpace(i_) && text_[i_] != '#') {
          ++i_;
          ++column_;
        }
        next_ = {text_.substr(start, i_ - start), line_, startColumn};
        has_ = true;
        return true;
      }
    }
    return false;
  }

  std::string_view text_;
  size_t i_ = 0;
  int line_ = 1, column_ = 1;
  Token next_, last_;
  bool has_ = false;
};

// Text as a message can show it: bytes outside printable ASCII become \xNN (a NUL would
// otherwise cut the message where it is printed, and a stray byte-order mark or control
// byte would be invisible), and a token from the file is cut to its first 40 bytes. A file
// name is never cut (PrintablePath): editors jump to the location a message gives.
std::string Printable(std::string_view s, size_t kShown = 40) {
  std::string out;
  for (size_t i = 0; i < s.size() && i < kShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (s.size() > kShown) out += "...";
  return out;
}


bool LooksNumeric(std::string_view s) {
  if (s.empty()) return false;
  const char c = s[0];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

// Thrown inside one statement to abandon it; the parser records the message and resumes at
// the next keyword.
struct StatementError {
  std::string message;
};

class NffParser {
 public:
  NffParser(std::string_view text, const std::string& fileName, NffErrors& errors)
      : tokens_(text), file_(PrintablePath(fileName)), errors_(errors) {}

  std::optional<Scene> Parse() {
    scene_.source = file_;
    while (!tokens_.AtEnd()) {
      const Token keyword = tokens_.Take();
      try {
        Statement(keyword);
      } catch (const StatementError& e) {
        Add(e.message);
        // Resume at the next token that is not a number: the next keyword.
        while (!tokens_.AtEnd() && LooksNumeric(tokens_.Peek().text)) tokens_.Take();
      }
      if (errors_.count >= kMaxNffErrors) {  // as compilers do: the rest would only repeat
        errors_.stoppedAtLine = keyword.line;
        break;
      }
    }
    if (errors_.stoppedAtLine == 0) CheckComplete();
    if (errors_.count > 0) return std::nullopt;
    return std::move(scene_);
  }

 private:
  std::string Where(const Token& t) const {
    return SourceLocation{file_, t.line, t.column}.ToString();
  }
  std::string WhereEnd() const {
    return SourceLocation{file_, tokens_.EndLine(), tokens_.EndColumn()}.ToString();
  }
  [[noreturn]] void Fail(const Token& at, const std::string& what) {
    throw StatementError{Where(at) + ": " + what};
  }
  // Counts every error; keeps the first kKeptNffErrors messages (memory stays bounded
  // whatever the file holds).
  void Add(std::string message) {
    ++errors_.count;
    if (errors_.messages.size() < kKeptNffErrors) errors_.messages.push_back(std::move(message));
  }
  void Report(const Token& at, const std::string& what) { Add(Where(at) + ": " + what); }

  Token Next(const char* what) {
    if (tokens_.AtEnd())
      throw StatementError{WhereEnd() + ": unexpected end of file, expected " + what};
    return tokens_.Take();
  }

  double Number(const char* what) {
    const Token t = Next(what);
    std::string_view s = t.text;
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    double value = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec == std::errc::result_out_of_range && end == s.data() + s.size()) {
      // Out of double's range either way: too large (overflow) or too small (underflow,
      // below the smallest normal 2.2e-308); say which.
      const std::string copy(s);
      const double nearest = std::strtod(copy.c_str(), nullptr);
      if (std::abs(nearest) < 1)
        Fail(t, std::string("expected a number for ") + what + ", got '" + Printable(t.text) +
                    "', which underflows double (its magnitude is below 2.2e-308; write 0 if that "
                    "is meant)");
      Fail(t, std::string("expected a finite number for ") + what + ", got '" + Printable(t.text) +
                  "', which overflows double (beyond 1.8e308)");
    }
    if (ec == std::errc() && end == s.data() + s.size() && !std::isfinite(value))
      Fail(t, std::string("expected a finite number for ") + what + ", got '" + Printable(t.text) +
                  "'");
    if (ec != std::errc() || end != s.data() + s.size())
      Fail(t, std::string("expected a number for ") + what + ", got '" + Printable(t.text) + "'");
    return value;
  }

  Vec3 Triple(const char* what) {
    Vec3 v;
    v.x = Number(what);
    v.y = Number(what);
    v.z = Number(what);
    return v;
  }

  long Integer(const char* what, long lo, long hi) {
    const Token t = tokens_.Peek();
    const double v = Number(what);
    if (v != std::floor(v) || v < double(lo) || v > double(hi))
      Fail(t, std::string("expected an integer from ") + std::to_string(lo) + " to " +
                  std::to_string(hi) + " for " + what + ", got '" + Printable(t.text) + "'");
    return long(v);
  }

  bool NextIsNumber() { return !tokens_.AtEnd() && LooksNumeric(tokens_.Peek().text); }

  void Once(bool& seen, const Token& keyword) {
    if (seen) Fail(keyword, "'" + Printable(keyword.text) + "' given twice");
    seen = true;
  }

  void Statement(const Token& k) {
    const std::string_view w = k.text;
    Camera& cam = scene_.camera;
    if (w == "v") {
      Once(seenV_, k);
    } else if (w == "from") {
      Once(seenFrom_, k);
      fromAt_ = k;
      cam.where = SourceLocation{file_, k.line, k.column};
      cam.from = Triple("the eye position 'from x y z'");
      readFrom_ = true;
    } else if (w == "at") {
      Once(seenAt_, k);
      atAt_ = k;
      cam.at = Triple("the look-at point 'at x y z'");
      readAt_ = true;
    } else if (w == "up") {
      Once(seenUp_, k);
      upAt_ = k;
      cam.up = Triple("the up vector 'up x y z'");
      readUp_ = true;
    } else if (w == "angle") {
      Once(seenAngle_, k);
      cam.angleDegrees = Number("the field of view 'angle degrees'");
      if (!(cam.angleDegrees > 0 && cam.angleDegrees < 180))
        Fail(k, "expected an angle strictly between 0 and 180 degrees");
    } else if (w == "hither") {
      Once(seenHither_, k);
      cam.hither = Number("the near distance 'hither h'");
      if (cam.hither < 0) Fail(k, "expected a hither distance >= 0");
    } else if (w == "resolution") {
      Once(seenResolution_, k);
      cam.width = int(Integer("the image width", 1, kMaxResolution));
      cam.height = int(Integer("the image height", 1, kMaxResolution));
    } else if (w == "b") {
      Once(seenBackground_, k);
      scene_.background = Colour("the background colour 'b r g b'", k);
    } else if (w == "l") {
      Light light;
      light.where = SourceLocation{file_, k.line, k.column};
      light.position = Triple("the light position 'l x y z [r g b]'");
      light.colourGiven = NextIsNumber();
      if (light.colourGiven) light.colour = Colour("the light colour", k);
      scene_.lights.push_back(light);
    } else if (w == "f") {
      MaterialStatement(k);
    } else if (w == "s") {
      Sphere s;
      s.centre = Triple("the sphere centre 's x y z r'");
      s.radius = Number("the sphere radius");
      if (!(s.radius > 0)) Fail(k, "expected a sphere radius > 0");
      AddObject(k, s);
    } else if (w == "c") {
      Cone c;
      c.base = Triple("the cone base 'c bx by bz br ax ay az ar'");
      c.baseRadius = Number("the cone base radius");
      c.apex = Triple("the cone apex");
      c.apexRadius = Number("the cone apex radius");
      if (c.baseRadius < 0 || c.apexRadius < 0) Fail(k, "expected cone radii >= 0");
      if (c.baseRadius == 0 && c.apexRadius == 0) Fail(k, "expected a cone radius > 0");
      const double h = Length(c.apex - c.base);
      if (!(h > 1e-12 * std::max({1.0, Length(c.base), c.baseRadius, c.apexRadius})))
        Fail(k, "expected a cone base and apex at different points");
      AddObject(k, c);
    } else if (w == "p" || w == "pp") {
      PolygonStatement(k, w == "pp");
    } else if (w == "transform") {
      TransformStatement(k);
    } else if (LooksNumeric(w)) {
      Fail(k,
           "expected a keyword (v, from, at, up, angle, hither, resolution, b, l, f, s, c, "
           "p, pp, transform), got the number '" +
               Printable(w) + "'");
    } else {
      Fail(k, "unknown keyword '" + Printable(w) +
                  "' (expected v, from, at, up, angle, hither, resolution, b, l, f, s, c, p, "
                  "pp or transform)");
    }
  }

  Vec3 Colour(const char* what, const Token& k) {
    const Vec3 c = Triple(what);
    if (c.x < 0 || c.y < 0 || c.z < 0) Fail(k, std::string("expected ") + what + " >= 0");
    return c;
  }

  // A number that must lie in [lo, hi] (hi = inf: no upper end); an error points at the
  // number itself and names the range.
  double NumberIn(const char* what, double lo, double hi) {
    const Token t = tokens_.Peek();
    const double v = Number(what);
    if (!(v >= lo && v <= hi)) {
      char range[64];
      if (std::isinf(hi))
        std::snprintf(range, sizeof range, ">= %g", lo);
      else
        std::snprintf(range, sizeof range, "from %g to %g", lo, hi);
      Fail(t, std::string("expected ") + what + " " + range + ", got '" + Printable(t.text) + "'");
    }
    return v;
  }

  // Every material value is checked against its own range, the same way (docs/scene-format.md):
  // the colour, Kd, Ks and T are fractions of light in [0, 1] (the NFF description: "usually
  // 0 <= Kd <= 1 and 0 <= Ks <= 1"; T above 1 would amplify the light through a surface);
  // Shine is an exponent >= 0; ior > 0, or 0 (SPD's value for opaque materials) when T = 0.
  void MaterialStatement(const Token& /*keyword: each value reports at its own token*/) {
    seenMaterial_ = true;  // even if malformed: do not also blame every following object
    Material m;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    m.colour.x = NumberIn("the material's red r", 0, 1);
    m.colour.y = NumberIn("the material's green g", 0, 1);
    m.colour.z = NumberIn("the material's blue b", 0, 1);
    m.kd = NumberIn("the diffuse weight Kd", 0, 1);
    m.ks = NumberIn("the specular and mirror weight Ks", 0, 1);
    m.shine = NumberIn("the Phong exponent Shine", 0, kInf);
    m.t = NumberIn("the transmission T", 0, 1);
    const Token iorToken = tokens_.Peek();
    m.ior = NumberIn("the index of refraction ior", 0, kInf);
    // SPD writes ior 0 for opaque materials; a transparent one needs a real index.
    if (m.t > 0 && !(m.ior > 0))
      Fail(iorToken,
           "expected an index of refraction ior > 0 for a transparent material (T > 0), got '" +
               Printable(iorToken.text) + "'");
    // Reuse an identical material (SPD files repeat `f` lines).
    auto it = std::find(scene_.materials.begin(), scene_.materials.end(), m);
    current_ = int(it - scene_.materials.begin());
    if (it == scene_.materials.end()) scene_.materials.push_back(m);
  }

  void PolygonStatement(const Token& k, bool withNormals) {
    const long n = Integer("the vertex count", 3, kMaxPolygonVertices);
    Polygon p;
    p.vertices.reserve(std::min<long>(n, 4096));
    for (long i = 0; i < n; ++i) {
      p.vertices.push_back(Triple("a polygon vertex"));
      if (withNormals) {
        const Token at = tokens_.Peek();
        const Vec3 nrm = Triple("a vertex normal");
        const double len = Length(nrm);
        if (!(len > 0) || !std::isfinite(len)) Fail(at, "expected a non-zero vertex normal");
        p.normals.push_back(nrm / len);
      }
    }
    const Vec3 normal = NewellNormal(p.vertices);  // its length is twice the area
    double size = 0;
    for (const Vec3& v : p.vertices) size = std::max(size, Length(v - p.vertices[0]));
    const double area2 = Length(normal);
    if (!std::isfinite(area2)) Fail(k, "polygon too large: its area overflows");
    if (!(size > 0) || !(area2 > 1e-12 * size * size)) {
      // SPD's teapot emits four zero-area triangles at the spout seam: they can never be
      // hit, so they are dropped with a warning rather than rejecting the sample scenes.
      scene_.warnings.push_back(Where(k) + ": warning: degenerate polygon (zero area) skipped");
      return;
    }
    const Vec3 unit = normal / area2;
    for (const Vec3& v : p.vertices) {
      if (std::abs(Dot(unit, v - p.vertices[0])) > 1e-4 * size)
        Fail(k, "non-planar polygon: vertices are off the plane by more than 1e-4 of its size");
    }
    AddObject(k, std::move(p));
  }

  void TransformStatement(const Token& k) {
    if (!tokens_.AtEnd() && tokens_.Peek().text == "identity") {
      tokens_.Take();
      transform_.reset();
      return;
    }
    Affine a;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        a.m[r][c] = Number("a 'transform' matrix entry (12 numbers, row by row)");
    // Judged free of the matrix's scale: a uniform 1e-152 is as regular as the identity
    // (its plain determinant, 1e-456, underflows to 0).
    const double det = a.RelativeDeterminant();
    if (!(std::abs(det) > 1e-12)) {
      char what[160];
      std::snprintf(what, sizeof what,
                    "singular transform: the 3x3 part divided by its largest entry "
                    "has determinant %.3g (expected |det| > 1e-12)",
                    det);
      Fail(k, what);
    }
    if (a.IsIdentity())
      transform_.reset();
    else
      transform_ = a;
  }

  void AddObject(const Token& k, Shape shape) {
    if (!seenMaterial_) Fail(k, "object before any material: expected an 'f' line first");
    Primitive p;
    p.shape = std::move(shape);
    p.material = current_;
    p.transform = transform_;
    p.where = SourceLocation{file_, k.line, k.column};
    scene_.objects.push_back(std::move(p));
  }

  void CheckComplete() {
    const std::string end = WhereEnd() + ": ";
    struct Need {
      bool seen;
      const char* what;
    };
    const Need needs[] = {{seenV_, "'v' (the view block)"},
                          {seenFrom_, "'from'"},
                          {seenAt_, "'at'"},
                          {seenUp_, "'up'"},
                          {seenAngle_, "'angle'"},
                          {seenHither_, "'hither'"},
                          {seenResolution_, "'resolution'"},
                          {seenBackground_, "'b' (background)"}};
    for (const Need& n : needs)
      if (!n.seen) Add(end + "missing " + std::string(n.what));
    if (readFrom_ && readAt_ && readUp_) {  // not when one of them was malformed (its own error)
      // Reported at the item's own line. Both vectors are scaled by their largest component
      // first, so the test cannot overflow.
      const Camera& c = scene_.camera;
      const Vec3 dir = ScaledDown(c.at * 0.5 - c.from * 0.5), up = ScaledDown(c.up);
      if (!(MaxAbs(dir) > 0)) {
        Report(fromAt_, "the view's 'from' equals 'at' (" + Where(atAt_) + "): no view direction");
      } else if (!(MaxAbs(up) > 0)) {
        Report(upAt_, "the view's 'up' is zero");
      } else if (!(Length(Cross(Normalize(dir), Normalize(up))) > 1e-9)) {
        Report(upAt_, "the view's 'up' is parallel to the view direction 'at' - 'from'");
      }
    }
    // Values whose squares overflow double would give a silently wrong image (an r² of
    // inf misses everything): rejected here with their line (docs/scene-format.md), also
    // when other lines have errors (the objects read whole are checked).
    if (const auto fault = FindMagnitudeOver(scene_, kMagnitudeLimitDouble)) {
      char what[320];
      std::snprintf(what, sizeof what,
                    ": %s reaches %.3g; every method squares coordinates in double, so values "
                    "must stay within %.0e (scale the scene down)",
                    fault->what.c_str(), fault->magnitude, kMagnitudeLimitDouble);
      Add(fault->where.ToString() + what);
    }
  }

  TokenStream tokens_;
  std::string file_;
  NffErrors& errors_;
  Scene scene_;
  int current_ = -1;
  std::optional<Affine> transform_;
  Token fromAt_, atAt_, upAt_;                               // where the view items were given
  bool readFrom_ = false, readAt_ = false, readUp_ = false;  // ... and read whole
  bool seenV_ = false, seenFrom_ = false, seenAt_ = false, seenUp_ = false, seenAngle_ = false,
       seenHither_ = false, seenResolution_ = false, seenBackground_ = false, seenMaterial_ = false;
};

}  // namespace

std::optional<Scene> ParseNff(std::string_view text, const std::string& fileName,
                              NffErrors& errors) {
  errors = NffErrors{};
  return NffParser(text, fileName, errors).Parse();
}

std::optional<Scene> ParseNff(std::string_view text, const std::string& fileName,
                              std::vector<std::string>& errors) {
  NffErrors all;
  std::optional<Scene> scene = ParseNff(text, fileName, all);
  errors = std::move(all.messages);
  return scene;
}

std::string NffErrors::Summary() const {
  std::string message = std::to_string(count) + (stoppedAtLine ? " or more" : "") + " error" +
                        (count > 1 ? "s" : "") + " in scene:";
  for (const std::string& m : messages) message += "\n  " + m;
  if (count > messages.size())
    message += "\n  ... and " + std::to_string(count - messages.size()) + " more";
  if (stoppedAtLine)
    message += "; reading stopped at line " + std::to_string(stoppedAtLine) + " after " +
               std::to_string(kMaxNffErrors) + " errors";
  return message;
}

Scene ParseNffOrThrow(std::string_view text, const std::string& fileName) {
  NffErrors errors;
  std::optional<Scene> scene = ParseNff(text, fileName, errors);
  if (scene) return std::move(*scene);
  throw UserError(errors.Summary());
}

Scene ReadNffFile(const std::string& path) {
  // Only a regular file is read (fixed/input_file.h): a directory would read as empty, and a
  // device or a pipe (/dev/zero) may never end. Its size is checked before any byte is read.
  return ParseNffOrThrow(
      ReadInputFile(path, {"the scene file", "an NFF scene file"}, kMaxSceneBytes), path);
}

namespace {
std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
std::string Nums(const Vec3& v) { return Num(v.x) + " " + Num(v.y) + " " + Num(v.z); }
}  // namespace

std::string WriteNff(const Scene& s) {
  std::string out;
  const Camera& c = s.camera;
  out += "b " + Nums(s.background) + "\n";
  out += "v\nfrom " + Nums(c.from) + "\nat " + Nums(c.at) + "\nup " + Nums(c.up) + "\nangle " +
         Num(c.angleDegrees) + "\nhither " + Num(c.hither) + "\nresolution " +
         std::to_string(c.width) + " " + std::to_string(c.height) + "\n";
  for (const Light& l : s.lights)
    out += "l " + Nums(l.position) + (l.colourGiven ? " " + Nums(l.colour) : std::string()) + "\n";
  int material = -1;
  std::optional<Affine> transform;
  for (const Primitive& o : s.objects) {
    if (o.material != material) {
      const Material& m = s.materials.at(o.material);
      out += "f " + Nums(m.colour) + " " + Num(m.kd) + " " + Num(m.ks) + " " + Num(m.shine) + " " +
             Num(m.t) + " " + Num(m.ior) + "\n";
      material = o.material;
    }
    const bool same = (o.transform.has_value() == transform.has_value()) &&
                      (!o.transform || std::equal(&o.transform->m[0][0], &o.transform->m[0][0] + 12,
                                                  &transform->m[0][0]));
    if (!same) {
      if (!o.transform) {
        out += "transform identity\n";
      } else {
        out += "transform";
        for (int r = 0; r < 3; ++r)
          for (int k = 0; k < 4; ++k) out += " " + Num(o.transform->m[r][k]);
        out += "\n";
      }
      transform = o.transform;
    }
    if (auto* sp = std::get_if<Sphere>(&o.shape)) {
      out += "s " + Nums(sp->centre) + " " + Num(sp->radius) + "\n";
    } else if (auto* cn = std::get_if<Cone>(&o.shape)) {
      out += "c\n" + Nums(cn->base) + " " + Num(cn->baseRadius) + "\n" + Nums(cn->apex) + " " +
             Num(cn->apexRadius) + "\n";
    } else if (auto* p = std::get_if<Polygon>(&o.shape)) {
      const bool pp = !p->normals.empty();
      out += (pp ? "pp " : "p ") + std::to_string(p->vertices.size()) + "\n";
      for (size_t i = 0; i < p->vertices.size(); ++i) {
        out += Nums(p->vertices[i]);
        if (pp) out += " " + Nums(p->normals[i]);
        out += "\n";
      }
    }
  }
  return out;
}

}  // namespace zephyr
