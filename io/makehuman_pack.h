#pragma once
// The compact MakeHuman source shipped in data/makehuman_body.bin: what rig/makehuman_body.h needs from the
// MakeHuman hm08 base mesh (CC0) to derive the default body, so the engine ships a modelled body and runs with no
// external data. ~0.27 MB, against 1.7 MB of base.obj and 1.1 MB of weights; written by apps/pack_makehuman.cpp
// from ../shared/data/makehuman_hm08 through load_makehuman (io/makehuman.h).
//
// Format, little-endian: "STMHPK01", u32 raw size, u32 packed size, then a zlib stream of
//   u32 vertices n, u32 triangles t, u32 joints j, f32 bbox min[3], f32 bbox extent[3], f32 joint centres[3j],
//   u16 positions[3n] (quantised over the box: 0.03 mm at 2 m), u16 triangles[3t], u8 part[n],
//   u8 influence joints[4n], u8 influence weights[4n] (x/255, renormalised on reading), then (version 2,
//   "STMHPK02") the texture coordinates: u32 extras e, u8 present, f32 uv box min[2] and extent[2], and when
//   present u16 uvs[2(n + e)] (quantised over the box: each vertex's own, its first corner's, then the e extra
//   values UV seams give other corners) and u16 corner codes[3t] (0: the vertex's own; k: extra k - 1).
//   Version 1 ("STMHPK01") ends at the weights and reads with no texture coordinates.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "components/mesh.h"
#include "io/obj.h"

namespace strata {

struct MakeHumanSource {
  std::vector<glm::vec3> positions;       // the file's A-pose, metres, soles at y = 0
  std::vector<std::uint32_t> triangles;   // a closed genus-0 surface (the hm08 "body" group, quads split)
  std::vector<std::uint16_t> part;        // per vertex, an index into paper_part_names()
  SkinBinding skin;                       // MakeHuman weights folded onto the default skeleton's joints
  std::vector<glm::vec3> joint_centers;   // per default-skeleton joint, its centre in the A-pose
  std::vector<glm::vec2> corner_uvs;      // per triangle corner (MakeHuman's texture coordinates), or empty
};

// From load_makehuman's result; throws std::invalid_argument if the body is not something the format can hold
// (more than 65,535 vertices, more than 255 joints, part names other than the paper's).
MakeHumanSource makehuman_source_from(const ImportedBody& body);

std::string pack_makehuman_source(const MakeHumanSource& source);
// Throws LoadError naming `name` and what is wrong (bad magic, sizes, a corrupt stream, an index out of range);
// nothing half-read is returned.
MakeHumanSource unpack_makehuman_source(std::string_view bytes, std::string_view name);

}  // namespace strata
