#pragma once
// ImpostorAtlas: a rig's walk cycle pre-rendered from many directions, which the renderer draws far walkers from
// (one textured quad each, render/impostor_pass.h) instead of skinning them. Baked once per rig through the
// engine's own renderer (render/impostor_bake.h) and cached on disk (io/impostor_file.h).
//
// Layout: one layer per gait phase (K layers, phase k = k / K of the cycle, left heel strike = 0). A layer is a
// grid of cells, `azimuths` across and `elevations` down; cell (a, e) shows the walker from azimuth
// 2 pi a / azimuths about +Y (0 = in front, the walker facing +Z; increasing counter-clockwise seen from above,
// towards +X) and elevation e / (elevations - 1) * max_elevation above the horizon, orthographically, the cell's
// vertical axis the world's up projected onto the image plane. Two images, RGBA8, rows top to bottom:
//   colour        dress weights premultiplied by coverage: r the top, g the bottom (shoes included: a few texels
//                 at this size), b hair, skin the rest (rig/surface_material.h); alpha = coverage. The renderer
//                 turns them into each walker's colours (render/appearance.h); at low quality, the skin colour
//   normal_depth  rgb = (normal * 0.5 + 0.5) * coverage, the normal in the walker's own frame (humanoid space,
//                 facing +Z); alpha = (depth / depth_range_m * 0.5 + 0.5) * coverage, depth the surface's
//                 distance in front of (+) or behind (-) the plane through the cell centre facing the viewer
// so impostors are lit by the same light as meshes and write a depth that sorts them against meshes and each
// other. Premultiplying keeps mipmaps free of the empty texels' colour: the shader divides by coverage.
//
// Why these choices: a per-phase layer is one texture-array lookup; the nearest phase and view rather than blends
// of neighbours, because blending two images of a walking figure shows two sets of limbs (Tecchia et al. picked
// the nearest view too); albedo and normal rather than a lit colour, because
// a baked lit image would carry the bake's light wherever the walker turns; weights rather than an albedo, because
// one atlas then dresses every walker in its own colours (weights filter and mip correctly, where class numbers
// would blend into a third class at every edge).
#include <cstddef>
#include <cstdint>
#include <vector>

namespace strata {

struct ImpostorAtlasLayout {
  int phases = 24;       // K: a ~1-s cycle at 30 fps changes phase every frame or two; the shader takes the
                         // nearest (blending neighbours ghosts the limbs)
  int azimuths = 32;     // 11.25 deg apart: the largest error, 5.6 deg. 16 (up to 11 deg off) measured 28.9 dB
                         // against 30.2 dB for the tiered eye-height crowd shot (report lod), where the walkers
                         // beyond the mesh budget stand close and large; more texels per cell did not help
  int elevations = 4;    // rows at 0, 25, 50, 75 deg: eye-height streets to views from above
  float max_elevation_deg = 75.0f;
  int cell_width = 64;   // pixels; the cell covers cell_width_m x cell_height_m
  int cell_height = 128;

  int layer_width() const { return azimuths * cell_width; }
  int layer_height() const { return elevations * cell_height; }
  std::size_t layer_bytes() const {
    return static_cast<std::size_t>(layer_width()) * static_cast<std::size_t>(layer_height()) * 4;
  }
  // Positive counts and sizes within what any GL 4.5 array texture holds.
  bool valid() const {
    return phases >= 1 && phases <= 256 && azimuths >= 1 && azimuths <= 64 && elevations >= 1 && elevations <= 16 &&
           cell_width >= 4 && cell_height >= 4 && layer_width() <= 8192 && layer_height() <= 8192 &&
           max_elevation_deg >= 0.0f && max_elevation_deg <= 90.0f;
  }
  friend bool operator==(const ImpostorAtlasLayout&, const ImpostorAtlasLayout&) = default;
};

struct ImpostorAtlas {
  ImpostorAtlasLayout layout;
  // World size (at walker scale 1, humanoid units) a cell covers, and the height of its centre above the ground
  // point of the walker's placement.
  float cell_width_m = 1.2f;
  float cell_height_m = 2.2f;
  float center_height_m = 0.9f;
  float depth_range_m = 0.8f;
  float speed_m_s = 0.0f;        // the walk baked (at the rig's own stature)
  std::uint64_t key = 0;         // what it was baked from (render/impostor_bake.h impostor_atlas_key)
  double bake_seconds = 0.0;     // time the bake took (0 when loaded from the cache)
  bool from_cache = false;
  std::vector<std::uint8_t> color;         // phases layers of layout.layer_bytes(), layer-major
  std::vector<std::uint8_t> normal_depth;  // the same layout

  std::size_t bytes() const { return color.size() + normal_depth.size(); }
  // Layout valid and both images the size it gives.
  bool complete() const {
    const std::size_t n = static_cast<std::size_t>(layout.phases) * layout.layer_bytes();
    return layout.valid() && color.size() == n && normal_depth.size() == n && cell_width_m > 0.0f &&
           cell_height_m > 0.0f && depth_range_m > 0.0f;
  }
};

}  // namespace strata
