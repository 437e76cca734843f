#include "io/makehuman_pack.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "io/load_error.h"

namespace strata {
namespace {

// Version 2 adds the texture coordinates; version 1 files (no UVs) still read.
constexpr char kPackMagic[8] = {'S', 'T', 'M', 'H', 'P', 'K', '0', '2'};
constexpr char kPackMagicV1[8] = {'S', 'T', 'M', 'H', 'P', 'K', '0', '1'};
// The hm08 body is 13,380 vertices; a bound keeps a corrupt header from asking for gigabytes.
constexpr std::uint32_t kMaxVertices = 65535, kMaxTriangles = 1u << 20, kMaxJoints = 255;

template <class T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

class Reader {
 public:
  Reader(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}
  template <class T>
  T get(const char* what) {
    if (bytes_.size() - at_ < sizeof(T)) fail(std::string("truncated in ") + what);
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  bool done() const { return at_ == bytes_.size(); }
  [[noreturn]] void fail(const std::string& what) const { throw LoadError(std::string(name_) + ": " + what); }

 private:
  std::string_view bytes_;
  std::string_view name_;
  std::size_t at_ = 0;
};

}  // namespace

MakeHumanSource makehuman_source_from(const ImportedBody& body) {
  const Mesh& mesh = body.mesh;
  if (mesh.vertex_count() > kMaxVertices) throw std::invalid_argument("makehuman pack: more than 65,535 vertices");
  if (body.skeleton.joint_count() > kMaxJoints) throw std::invalid_argument("makehuman pack: more than 255 joints");
  const auto& paper = paper_part_names();
  std::vector<std::uint16_t> to_paper(mesh.part_names.size());
  for (std::size_t p = 0; p < mesh.part_names.size(); ++p) {
    const auto it = std::find(paper.begin(), paper.end(), mesh.part_names[p]);
    if (it == paper.end()) throw std::invalid_argument("makehuman pack: part '" + mesh.part_names[p] + "' is not a paper part");
    to_paper[p] = static_cast<std::uint16_t>(it - paper.begin());
  }
  MakeHumanSource s;
  s.positions = mesh.positions;
  s.triangles = mesh.triangles;
  s.part.resize(mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) s.part[v] = to_paper[mesh.part[v]];
  s.skin = body.skin;
  s.joint_centers = body.skeleton.centers;
  s.corner_uvs = mesh.corner_uvs;
  return s;
}

std::string pack_makehuman_source(const MakeHumanSource& s) {
  const std::uint32_t n = static_cast<std::uint32_t>(s.positions.size());
  const std::uint32_t t = static_cast<std::uint32_t>(s.triangles.size() / 3);
  const std::uint32_t j = static_cast<std::uint32_t>(s.joint_centers.size());
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const glm::vec3& p : s.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-6f));
  std::string raw;
  for (std::uint32_t v : {n, t, j}) put(raw, v);
  for (int k = 0; k < 3; ++k) put(raw, lo[k]);
  for (int k = 0; k < 3; ++k) put(raw, extent[k]);
  for (const glm::vec3& c : s.joint_centers)
    for (int k = 0; k < 3; ++k) put(raw, c[k]);
  for (const glm::vec3& p : s.positions)
    for (int k = 0; k < 3; ++k)
      put(raw, static_cast<std::uint16_t>(std::lround(std::clamp((p[k] - lo[k]) / extent[k], 0.0f, 1.0f) * 65535.0f)));
  for (std::uint32_t i : s.triangles) put(raw, static_cast<std::uint16_t>(i));
  for (std::uint16_t p : s.part) put(raw, static_cast<std::uint8_t>(p));
  for (const auto& js : s.skin.joints)
    for (std::int16_t x : js) put(raw, static_cast<std::uint8_t>(x));
  for (const auto& ws : s.skin.weights)
    for (float w : ws) put(raw, static_cast<std::uint8_t>(std::lround(std::clamp(w, 0.0f, 1.0f) * 255.0f)));
  // Texture coordinates: each vertex's own (its first corner's), then the extra values seams give some corners,
  // all quantised over their box; then per corner 0 for its vertex's own value or k for extra k - 1. Nearly every
  // corner is 0, which zlib shrinks to almost nothing (an index per corner into one table took 170 KB).
  if (!s.corner_uvs.empty() && s.corner_uvs.size() != s.triangles.size())
    throw std::invalid_argument("makehuman pack: corner uvs do not match the triangles");
  std::vector<glm::vec2> table;
  std::vector<std::uint16_t> corner_code;
  if (!s.corner_uvs.empty()) {
    table.assign(n, glm::vec2(0.0f));
    std::vector<std::uint8_t> has(n, 0);
    for (std::size_t c = 0; c < s.triangles.size(); ++c)
      if (s.triangles[c] < n && !has[s.triangles[c]]) has[s.triangles[c]] = 1, table[s.triangles[c]] = s.corner_uvs[c];
    for (std::size_t c = 0; c < s.triangles.size(); ++c) {
      const glm::vec2 u = s.corner_uvs[c];
      // (An index out of range is written as it is, for the reader to refuse.)
      if (s.triangles[c] >= n || u == table[s.triangles[c]]) {
        corner_code.push_back(0);
        continue;
      }
      std::size_t k = n;
      while (k < table.size() && table[k] != u) ++k;  // a few hundred extras: linear is fine
      if (k == table.size()) table.push_back(u);
      if (k - n + 1 > 65535) throw std::invalid_argument("makehuman pack: more than 65,535 seam texture coordinates");
      corner_code.push_back(static_cast<std::uint16_t>(k - n + 1));
    }
  }
  glm::vec2 uv_lo(0.0f), uv_extent(1.0f);
  if (!table.empty()) {
    glm::vec2 uv_hi(-std::numeric_limits<float>::max());
    uv_lo = glm::vec2(std::numeric_limits<float>::max());
    for (const glm::vec2& u : table) uv_lo = glm::min(uv_lo, u), uv_hi = glm::max(uv_hi, u);
    uv_extent = glm::max(uv_hi - uv_lo, glm::vec2(1e-6f));
  }
  put(raw, static_cast<std::uint32_t>(table.size() > n ? table.size() - n : 0));  // extras
  put(raw, static_cast<std::uint8_t>(table.empty() ? 0 : 1));
  for (int k = 0; k < 2; ++k) put(raw, uv_lo[k]);
  for (int k = 0; k < 2; ++k) put(raw, uv_extent[k]);
  for (const glm::vec2& u : table)
    for (int k = 0; k < 2; ++k)
      put(raw, static_cast<std::uint16_t>(std::lround(std::clamp((u[k] - uv_lo[k]) / uv_extent[k], 0.0f, 1.0f) * 65535.0f)));
  for (const std::uint16_t code : corner_code) put(raw, code);
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), 9) != Z_OK)
    throw std::runtime_error("makehuman pack: zlib failed");
  packed.resize(packed_size);
  std::string out(kPackMagic, sizeof kPackMagic);
  put(out, static_cast<std::uint32_t>(raw.size()));
  put(out, static_cast<std::uint32_t>(packed_size));
  return out + packed;
}

MakeHumanSource unpack_makehuman_source(std::string_view bytes, std::string_view name) {
  Reader head(bytes, name);
  char magic[sizeof kPackMagic];
  for (char& c : magic) c = head.get<char>("the magic");
  const bool with_uvs = std::memcmp(magic, kPackMagic, sizeof kPackMagic) == 0;
  if (!with_uvs && std::memcmp(magic, kPackMagicV1, sizeof kPackMagicV1) != 0)
    head.fail("not a packed MakeHuman body (bad magic)");
  const auto raw_size = head.get<std::uint32_t>("the header");
  const auto packed_size = head.get<std::uint32_t>("the header");
  const std::size_t offset = sizeof kPackMagic + 8;
  if (bytes.size() - offset != packed_size) head.fail("the stream is " + std::to_string(bytes.size() - offset) +
                                                     " bytes, the header says " + std::to_string(packed_size));
  if (raw_size > (64u << 20)) head.fail("raw size " + std::to_string(raw_size) + " is beyond any body");
  std::string raw(raw_size, '\0');
  uLongf got = raw_size;
  if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &got, reinterpret_cast<const Bytef*>(bytes.data() + offset),
                 packed_size) != Z_OK ||
      got != raw_size)
    head.fail("corrupt zlib stream");

  Reader r(raw, name);
  const auto n = r.get<std::uint32_t>("the counts"), t = r.get<std::uint32_t>("the counts"),
             j = r.get<std::uint32_t>("the counts");
  if (n == 0 || n > kMaxVertices || t == 0 || t > kMaxTriangles || j == 0 || j > kMaxJoints)
    r.fail("counts out of range (vertices " + std::to_string(n) + ", triangles " + std::to_string(t) + ", joints " +
           std::to_string(j) + ")");
  glm::vec3 lo, extent;
  for (int k = 0; k < 3; ++k) lo[k] = r.get<float>("the box");
  for (int k = 0; k < 3; ++k) extent[k] = r.get<float>("the box");
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(lo[k]) || !std::isfinite(extent[k]) || extent[k] <= 0.0f || extent[k] > 100.0f)
      r.fail("bad bounding box");
  MakeHumanSource s;
  s.joint_centers.resize(j);
  for (glm::vec3& c : s.joint_centers)
    for (int k = 0; k < 3; ++k) {
      c[k] = r.get<float>("the joint centres");
      if (!std::isfinite(c[k])) r.fail("joint centre not finite");
    }
  s.positions.resize(n);
  for (glm::vec3& p : s.positions)
    for (int k = 0; k < 3; ++k) p[k] = lo[k] + extent[k] * (static_cast<float>(r.get<std::uint16_t>("positions")) / 65535.0f);
  s.triangles.resize(3 * static_cast<std::size_t>(t));
  for (std::uint32_t& i : s.triangles) {
    i = r.get<std::uint16_t>("triangles");
    if (i >= n) r.fail("triangle index " + std::to_string(i) + " >= " + std::to_string(n) + " vertices");
  }
  s.part.resize(n);
  for (std::uint16_t& p : s.part) {
    p = r.get<std::uint8_t>("parts");
    if (p >= paper_part_names().size()) r.fail("part " + std::to_string(p) + " is not one of the paper's 53");
  }
  s.skin.joints.resize(n);
  s.skin.weights.resize(n);
  for (auto& js : s.skin.joints)
    for (std::int16_t& x : js) {
      x = r.get<std::uint8_t>("influence joints");
      if (static_cast<std::uint32_t>(x) >= j) r.fail("influence joint " + std::to_string(x) + " >= " + std::to_string(j));
    }
  for (std::size_t v = 0; v < n; ++v) {
    float sum = 0.0f;
    for (float& w : s.skin.weights[v]) sum += (w = r.get<std::uint8_t>("influence weights") / 255.0f);
    if (sum <= 0.0f) r.fail("vertex " + std::to_string(v) + " has no weight");
    for (int k = 0; k < kMaxInfluences; ++k) {
      s.skin.weights[v][k] /= sum;
      if (s.skin.weights[v][k] == 0.0f) s.skin.joints[v][k] = 0;
    }
  }
  if (with_uvs) {
    const auto extras = r.get<std::uint32_t>("the texture coordinates");
    const auto present = r.get<std::uint8_t>("the texture coordinates");
    if (extras > kMaxVertices || present > 1 || (!present && extras))
      r.fail("bad texture coordinate counts (" + std::to_string(extras) + " extra)");
    glm::vec2 uv_lo, uv_extent;
    for (int k = 0; k < 2; ++k) uv_lo[k] = r.get<float>("the texture coordinates' box");
    for (int k = 0; k < 2; ++k) uv_extent[k] = r.get<float>("the texture coordinates' box");
    for (int k = 0; k < 2; ++k)
      if (!std::isfinite(uv_lo[k]) || !std::isfinite(uv_extent[k]) || uv_extent[k] <= 0.0f || uv_extent[k] > 1e4f)
        r.fail("bad texture coordinate box");
    if (present) {
      std::vector<glm::vec2> table(n + extras);
      for (glm::vec2& d : table)
        for (int k = 0; k < 2; ++k)
          d[k] = uv_lo[k] + uv_extent[k] * (static_cast<float>(r.get<std::uint16_t>("texture coordinates")) / 65535.0f);
      s.corner_uvs.resize(s.triangles.size());
      for (std::size_t c = 0; c < s.corner_uvs.size(); ++c) {
        const auto code = r.get<std::uint16_t>("corner texture coordinates");
        if (code > extras) r.fail("corner texture coordinate " + std::to_string(code) + " > " + std::to_string(extras) + " extras");
        s.corner_uvs[c] = code == 0 ? table[s.triangles[c]] : table[n + code - 1u];
      }
    }
  }
  if (!r.done()) r.fail(with_uvs ? "trailing bytes after the texture coordinates" : "trailing bytes after the weights");
  return s;
}

}  // namespace strata
