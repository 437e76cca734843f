#include "io/obj.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "io/mesh_check.h"

namespace strata {
namespace {

struct Corner {
  std::int32_t v = -1, vt = -1, vn = -1;  // 0-based, -1 when absent
};

struct Triangle {
  Corner c[3];
  std::uint32_t group = 0;
};

bool is_field_separator(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Splits a line into whitespace-separated tokens (views into the line).
void tokenize(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_field_separator(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_field_separator(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
}

class ObjParser {
 public:
  ObjParser(std::string_view source, const ObjOptions& options) : source_(source), options_(options) {}

  Mesh parse(std::string_view text, ObjSource* source) {
    std::size_t pos = 0;
    std::vector<std::string_view> tokens;
    while (pos <= text.size()) {
      const std::size_t end = std::min(text.find('\n', pos), text.size());
      std::string_view line = text.substr(pos, end - pos);
      ++line_;
      pos = end + 1;
      if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      tokenize(line, tokens);
      if (!tokens.empty()) statement(tokens);
      if (end == text.size()) break;
    }
    Mesh mesh = build(source);
    if (source) {
      source->file_positions = std::move(positions_);
      for (glm::vec3& p : source->file_positions) p *= options_.scale;
    }
    return mesh;
  }

 private:
  [[noreturn]] void fail(const std::string& what, const std::string& reason) const {
    throw LoadError(source_ + ":" + std::to_string(line_) + ": " + what + ": " + reason);
  }

  float number(std::string_view token, const char* what) const {
    if (!token.empty() && token.front() == '+') token.remove_prefix(1);  // from_chars rejects a leading '+'
    float value = 0.0f;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size())
      fail(what, "malformed number '" + std::string(token) + "'");
    if (!std::isfinite(value)) fail(what, "non-finite coordinate '" + std::string(token) + "'");
    return value;
  }

  // Resolves one OBJ index (1-based, or negative = relative to the elements read so far) to 0-based.
  std::int32_t index(std::string_view token, std::size_t count, const char* kind) const {
    long value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size())
      fail("f", std::string("malformed ") + kind + " index '" + std::string(token) + "'");
    const long resolved = value < 0 ? static_cast<long>(count) + value : value - 1;
    if (value == 0 || resolved < 0 || resolved >= static_cast<long>(count))
      fail("f", std::string(kind) + " index " + std::to_string(value) + " out of range (" + std::to_string(count) +
                    " " + kind + " defined so far)");
    return static_cast<std::int32_t>(resolved);
  }

  Corner corner(std::string_view token) const {
    Corner c;
    const std::size_t s1 = token.find('/');
    c.v = index(token.substr(0, s1), positions_.size(), "v");
    if (s1 == std::string_view::npos) return c;
    const std::string_view rest = token.substr(s1 + 1);
    const std::size_t s2 = rest.find('/');
    const std::string_view vt = rest.substr(0, s2);
    if (!vt.empty()) c.vt = index(vt, uvs_.size(), "vt");
    if (s2 != std::string_view::npos) {
      const std::string_view vn = rest.substr(s2 + 1);
      if (!vn.empty()) c.vn = index(vn, normals_.size(), "vn");
    }
    return c;
  }

  void start_group(std::string_view name) {
    const auto [it, inserted] = group_ids_.try_emplace(std::string(name), static_cast<std::uint32_t>(group_names_.size()));
    if (inserted) {
      group_names_.emplace_back(name);
      group_faces_.push_back(0);
    }
    group_ = it->second;
  }

  void statement(const std::vector<std::string_view>& t) {
    const std::string_view kw = t[0];
    if (kw == "v") {
      if (t.size() < 4) fail("v", "expected 3 coordinates, got " + std::to_string(t.size() - 1));
      positions_.emplace_back(number(t[1], "v"), number(t[2], "v"), number(t[3], "v"));
    } else if (kw == "vt") {
      if (t.size() < 3) fail("vt", "expected at least 2 coordinates, got " + std::to_string(t.size() - 1));
      uvs_.emplace_back(number(t[1], "vt"), number(t[2], "vt"));
    } else if (kw == "vn") {
      if (t.size() < 4) fail("vn", "expected 3 coordinates, got " + std::to_string(t.size() - 1));
      normals_.emplace_back(number(t[1], "vn"), number(t[2], "vn"), number(t[3], "vn"));
    } else if (kw == "f") {
      if (t.size() < 4) fail("f", "a face needs at least 3 vertices, got " + std::to_string(t.size() - 1));
      if (group_names_.empty()) start_group("default");
      corners_.clear();
      for (std::size_t i = 1; i < t.size(); ++i) corners_.push_back(corner(t[i]));
      for (std::size_t i = 1; i + 1 < corners_.size(); ++i)
        triangles_.push_back({{corners_[0], corners_[i], corners_[i + 1]}, group_});
      ++group_faces_[group_];
    } else if (kw == "g" || kw == "o") {
      start_group(t.size() > 1 ? t[1] : std::string_view("default"));
    }
  }

  Mesh build(ObjSource* source) {
    const std::string& src = source_;
    std::vector<char> keep_group(group_names_.size(), options_.groups.empty() ? 1 : 0);
    for (const std::string& wanted : options_.groups) {
      const auto it = group_ids_.find(wanted);
      if (it == group_ids_.end()) throw LoadError(src + ": group '" + wanted + "': requested but not in the file");
      if (group_faces_[it->second] == 0) throw LoadError(src + ": group '" + wanted + "': requested but has no faces");
      keep_group[it->second] = 1;
    }

    // Parts in order of first appearance among kept faces; vertices renumbered in file order.
    std::vector<std::int32_t> part_of_group(group_names_.size(), -1);
    std::vector<std::int32_t> vertex_part(positions_.size(), -1);
    Mesh mesh;
    mesh.name = src;
    for (const Triangle& tri : triangles_) {
      if (!keep_group[tri.group]) continue;
      if (part_of_group[tri.group] < 0) {
        part_of_group[tri.group] = static_cast<std::int32_t>(mesh.part_names.size());
        mesh.part_names.push_back(group_names_[tri.group]);
      }
      for (const Corner& c : tri.c)
        if (vertex_part[c.v] < 0) vertex_part[c.v] = part_of_group[tri.group];
    }
    if (mesh.part_names.size() > 65535) throw LoadError(src + ": more than 65535 groups");
    std::vector<std::int32_t> remap(positions_.size(), -1);
    for (std::size_t v = 0; v < positions_.size(); ++v) {
      if (vertex_part[v] < 0) continue;
      remap[v] = static_cast<std::int32_t>(mesh.positions.size());
      if (source) source->file_vertex.push_back(static_cast<std::uint32_t>(v));
      mesh.positions.push_back(positions_[v] * options_.scale);
      mesh.part.push_back(static_cast<std::uint16_t>(vertex_part[v]));
    }

    // A per-vertex attribute survives only if every corner of a vertex names the same value.
    const std::size_t n = mesh.positions.size();
    std::vector<std::int32_t> uv_of(n, -1), normal_of(n, -1);
    bool uv_ok = true, normal_ok = true, corner_uv_ok = true;
    auto consistent = [](std::int32_t& slot, std::int32_t index, auto const& values) {
      if (index < 0) return false;
      if (slot < 0 || slot == index) {
        slot = index;
        return true;
      }
      return values[slot] == values[index];
    };
    for (const Triangle& tri : triangles_) {
      if (!keep_group[tri.group]) continue;
      for (const Corner& c : tri.c) {
        const std::uint32_t v = static_cast<std::uint32_t>(remap[c.v]);
        mesh.triangles.push_back(v);
        // Face-varying: every corner with its own vt, seams allowed.
        if (corner_uv_ok && c.vt >= 0) mesh.corner_uvs.push_back(uvs_[static_cast<std::size_t>(c.vt)]);
        corner_uv_ok = corner_uv_ok && c.vt >= 0;
        if (uv_ok) uv_ok = consistent(uv_of[v], c.vt, uvs_);
        if (normal_ok) normal_ok = consistent(normal_of[v], c.vn, normals_);
      }
    }
    if (!corner_uv_ok) mesh.corner_uvs.clear();
    if (uv_ok && n > 0) {
      mesh.uvs.resize(n);
      for (std::size_t v = 0; v < n; ++v) mesh.uvs[v] = uvs_[uv_of[v]];
    }
    if (normal_ok && n > 0) {
      mesh.normals.resize(n);
      for (std::size_t v = 0; v < n; ++v) {
        const float len = glm::length(normals_[normal_of[v]]);
        mesh.normals[v] = len > 1e-20f ? normals_[normal_of[v]] / len : glm::vec3(0.0f, 1.0f, 0.0f);
      }
      // A mirroring (negative) scale would flip the winding but not the stored normals: recompute instead.
      if (options_.scale < 0.0f) mesh.normals.clear();
    }
    if (mesh.normals.empty()) compute_normals(mesh);
    validate_mesh(mesh, src);
    return mesh;
  }

  std::string source_;
  const ObjOptions& options_;
  std::size_t line_ = 0;
  std::vector<glm::vec3> positions_, normals_;
  std::vector<glm::vec2> uvs_;
  std::vector<Triangle> triangles_;
  std::vector<Corner> corners_;
  std::vector<std::string> group_names_;
  std::vector<std::size_t> group_faces_;
  std::unordered_map<std::string, std::uint32_t> group_ids_;
  std::uint32_t group_ = 0;
};

}  // namespace

Mesh load_obj_text(std::string_view text, std::string_view source_name, const ObjOptions& options,
                   ObjSource* source) {
  // Filled into a local so that a throw leaves the caller's ObjSource untouched.
  ObjSource local;
  Mesh mesh = ObjParser(source_name, options).parse(text, source ? &local : nullptr);
  if (source) *source = std::move(local);
  return mesh;
}

Mesh load_obj_file(const std::filesystem::path& path, const ObjOptions& options, ObjSource* source) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path.string() + ": cannot open file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return load_obj_text(buffer.str(), path.filename().string(), options, source);
}

}  // namespace strata
