#include "rig/body_cache.h"

#include "components/fnv_hasher.h"
#include "io/mesh_check.h"
#include "io/atomic_file.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <type_traits>

#include <unistd.h>

namespace strata {
namespace {

// Version 2: meshes carry corner_uvs.
constexpr char kMagic[8] = {'S', 'T', 'R', 'B', 'O', 'D', 'Y', '2'};
constexpr std::uint64_t kMaxElements = 1u << 26;  // refuses absurd counts from a corrupt file before allocating


template <class T>
void write_vector(std::ofstream& out, const std::vector<T>& v) {
  const std::uint64_t n = v.size();
  out.write(reinterpret_cast<const char*>(&n), sizeof n);
  out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
}

template <class T>
bool read_vector(std::ifstream& in, std::vector<T>& v) {
  std::uint64_t n = 0;
  if (!in.read(reinterpret_cast<char*>(&n), sizeof n) || n > kMaxElements) return false;
  v.resize(n);
  return static_cast<bool>(in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T))));
}

void write_string(std::ofstream& out, const std::string& s) {
  write_vector(out, std::vector<char>(s.begin(), s.end()));
}

bool read_string(std::ifstream& in, std::string& s) {
  std::vector<char> chars;
  if (!read_vector(in, chars)) return false;
  s.assign(chars.begin(), chars.end());
  return true;
}

void write_mesh(std::ofstream& out, const Mesh& m) {
  write_string(out, m.name);
  write_vector(out, m.positions);
  write_vector(out, m.normals);
  write_vector(out, m.uvs);
  write_vector(out, m.corner_uvs);
  write_vector(out, m.triangles);
  write_vector(out, m.part);
  write_vector(out, std::vector<std::uint64_t>{m.part_names.size()});
  for (const std::string& name : m.part_names) write_string(out, name);
}

bool read_mesh(std::ifstream& in, Mesh& m) {
  std::vector<std::uint64_t> parts;
  if (!read_string(in, m.name) || !read_vector(in, m.positions) || !read_vector(in, m.normals) ||
      !read_vector(in, m.uvs) || !read_vector(in, m.corner_uvs) || !read_vector(in, m.triangles) || !read_vector(in, m.part) ||
      !read_vector(in, parts) || parts.size() != 1 || parts[0] > 4096)
    return false;
  m.part_names.resize(parts[0]);
  for (std::string& name : m.part_names)
    if (!read_string(in, name)) return false;
  try {
    validate_mesh(m, "body cache");
  } catch (const std::exception&) {
    return false;
  }
  return m.normals.size() == m.positions.size();
}

}  // namespace

std::uint64_t body_cache_key(const Skeleton& skeleton, const BodyOptions& options, std::uint32_t version) {
  FnvHasher h;
  h.value(version);
  h.value(options.grid_cell);
  h.value(options.level_vertices);
  h.value(options.cage_vertices);
  for (std::size_t j = 0; j < skeleton.joint_count(); ++j) {
    h.bytes(skeleton.joint_names[j].data(), skeleton.joint_names[j].size());
    h.value(skeleton.parents[j]);
    h.value(skeleton.centers[j]);
  }
  for (const SkeletonSite& site : skeleton.sites) {
    h.bytes(site.name.data(), site.name.size());
    h.value(site.position);
  }
  return h.h;
}

std::optional<std::filesystem::path> body_cache_directory() {
  const char* off = std::getenv("STRATA_NO_BODY_CACHE");
  if (off && *off && std::string(off) != "0") return std::nullopt;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "strata";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".cache" / "strata";
  return std::nullopt;
}

std::optional<std::vector<float>> load_float_cache(const std::filesystem::path& file, const char (&magic)[8],
                                                   std::uint64_t key, std::size_t floats_per_item,
                                                   std::uint64_t max_items) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  char stored_magic[8];
  std::uint64_t stored_key = 0, count = 0;
  if (!in.read(stored_magic, sizeof stored_magic) || std::memcmp(stored_magic, magic, sizeof stored_magic) != 0)
    return std::nullopt;
  if (!in.read(reinterpret_cast<char*>(&stored_key), sizeof stored_key) || stored_key != key) return std::nullopt;
  if (!in.read(reinterpret_cast<char*>(&count), sizeof count) || count > max_items) return std::nullopt;
  std::vector<float> values(static_cast<std::size_t>(count) * floats_per_item);
  if (!in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float))))
    return std::nullopt;
  for (float v : values)
    if (!std::isfinite(v)) return std::nullopt;
  return values;
}

void save_float_cache(const std::filesystem::path& file, const char (&magic)[8], std::uint64_t key,
                      std::size_t floats_per_item, std::span<const float> values) {
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec || floats_per_item == 0) return;
  AtomicFile atomic(file);
  {
    std::ofstream out(atomic.temp_path(), std::ios::binary | std::ios::trunc);
    if (!out) return;
    const std::uint64_t count = values.size() / floats_per_item;
    out.write(magic, sizeof magic);
    out.write(reinterpret_cast<const char*>(&key), sizeof key);
    out.write(reinterpret_cast<const char*>(&count), sizeof count);
    out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(count * floats_per_item * sizeof(float)));
    out.close();
    if (!out) return;
  }
  try {
    atomic.commit();
  } catch (const std::exception&) {
  }
}

std::optional<BodyLevels> load_body_cache(const std::filesystem::path& file, std::uint64_t key) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  char magic[sizeof kMagic];
  std::uint64_t stored_key = 0;
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0) return std::nullopt;
  if (!in.read(reinterpret_cast<char*>(&stored_key), sizeof stored_key) || stored_key != key) return std::nullopt;
  BodyLevels levels;
  for (Mesh& m : levels.levels)
    if (!read_mesh(in, m)) return std::nullopt;
  if (!read_mesh(in, levels.cage)) return std::nullopt;
  return levels;
}

void save_body_cache(const std::filesystem::path& file, std::uint64_t key, const BodyLevels& levels) {
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec) return;
  // A temporary sibling renamed into place (io/atomic_file.h): concurrent processes (parallel tests) never see
  // half a file. The cache is an optimisation, so a failure is silent: the next start regenerates the body.
  AtomicFile atomic(file);
  {
    std::ofstream out(atomic.temp_path(), std::ios::binary | std::ios::trunc);
    if (!out) return;
    out.write(kMagic, sizeof kMagic);
    out.write(reinterpret_cast<const char*>(&key), sizeof key);
    for (const Mesh& m : levels.levels) write_mesh(out, m);
    write_mesh(out, levels.cage);
    out.close();
    if (!out) return;
  }
  try {
    atomic.commit();
  } catch (const std::exception&) {
  }
}

BodyLevels cached_body_levels(std::string_view stem, std::uint64_t key, const std::function<BodyLevels()>& make) {
  const auto directory = body_cache_directory();
  char hex[32];  // "_" + 16 hex digits + ".bin" + NUL = 22 (20 cut the names to ".b")
  std::snprintf(hex, sizeof hex, "_%016llx.bin", static_cast<unsigned long long>(key));
  const std::filesystem::path file = directory ? *directory / (std::string(stem) + hex) : std::filesystem::path();
  if (directory)
    if (std::optional<BodyLevels> cached = load_body_cache(file, key)) return std::move(*cached);
  BodyLevels made = make();
  if (directory) save_body_cache(file, key, made);
  return made;
}

}  // namespace strata
