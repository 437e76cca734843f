#include "io/impostor_file.h"

#include <zlib.h>

#include <cstring>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "io/atomic_file.h"

namespace strata {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'I', 'M', 'P', '0', '1'};

struct Header {
  std::uint64_t key;
  std::int32_t phases, azimuths, elevations, cell_width, cell_height;
  float max_elevation_deg, cell_width_m, cell_height_m, center_height_m, depth_range_m, speed_m_s;
};

bool write_blob(std::ofstream& out, const std::vector<std::uint8_t>& raw) {
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<std::uint8_t> packed(packed_size);
  // Level 1: the images are mostly zeros, which any level squeezes; higher levels cost seconds for ~10 %.
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()), 1) != Z_OK) return false;
  const std::uint64_t sizes[2] = {raw.size(), packed_size};
  out.write(reinterpret_cast<const char*>(sizes), sizeof sizes);
  out.write(reinterpret_cast<const char*>(packed.data()), static_cast<std::streamsize>(packed_size));
  return static_cast<bool>(out);
}

bool read_blob(std::ifstream& in, std::size_t expected, std::vector<std::uint8_t>& raw) {
  std::uint64_t sizes[2] = {0, 0};
  if (!in.read(reinterpret_cast<char*>(sizes), sizeof sizes)) return false;
  // The raw size is known from the layout; the packed size can never exceed zlib's bound for it.
  if (sizes[0] != expected || sizes[1] > compressBound(static_cast<uLong>(expected))) return false;
  std::vector<std::uint8_t> packed(sizes[1]);
  if (!in.read(reinterpret_cast<char*>(packed.data()), static_cast<std::streamsize>(sizes[1]))) return false;
  raw.resize(expected);
  uLongf raw_size = static_cast<uLongf>(expected);
  return uncompress(raw.data(), &raw_size, packed.data(), static_cast<uLong>(sizes[1])) == Z_OK &&
         raw_size == expected;
}

}  // namespace

std::optional<ImpostorAtlas> load_impostor_atlas(const std::filesystem::path& file, std::uint64_t key) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  char magic[sizeof kMagic];
  Header h{};
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0) return std::nullopt;
  if (!in.read(reinterpret_cast<char*>(&h), sizeof h) || h.key != key) return std::nullopt;
  ImpostorAtlas atlas;
  atlas.layout = {h.phases, h.azimuths, h.elevations, h.max_elevation_deg, h.cell_width, h.cell_height};
  if (!atlas.layout.valid()) return std::nullopt;
  atlas.cell_width_m = h.cell_width_m;
  atlas.cell_height_m = h.cell_height_m;
  atlas.center_height_m = h.center_height_m;
  atlas.depth_range_m = h.depth_range_m;
  atlas.speed_m_s = h.speed_m_s;
  atlas.key = key;
  atlas.from_cache = true;
  const std::size_t n = static_cast<std::size_t>(atlas.layout.phases) * atlas.layout.layer_bytes();
  if (!read_blob(in, n, atlas.color) || !read_blob(in, n, atlas.normal_depth)) return std::nullopt;
  if (!atlas.complete()) return std::nullopt;
  return atlas;
}

bool save_impostor_atlas(const std::filesystem::path& file, const ImpostorAtlas& atlas) {
  if (!atlas.complete()) return false;
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  if (ec) return false;
  try {
    AtomicFile atomic(file);
    {
      std::ofstream out(atomic.temp_path(), std::ios::binary | std::ios::trunc);
      if (!out) return false;
      const ImpostorAtlasLayout& l = atlas.layout;
      const Header h{atlas.key, l.phases, l.azimuths, l.elevations, l.cell_width, l.cell_height,
                     l.max_elevation_deg, atlas.cell_width_m, atlas.cell_height_m, atlas.center_height_m,
                     atlas.depth_range_m, atlas.speed_m_s};
      out.write(kMagic, sizeof kMagic);
      out.write(reinterpret_cast<const char*>(&h), sizeof h);
      if (!write_blob(out, atlas.color) || !write_blob(out, atlas.normal_depth)) return false;
      out.close();
      if (!out) return false;
    }
    atomic.commit();
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace strata
