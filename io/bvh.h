#pragma once
// Reading Biovision Hierarchy (BVH) motion capture: a HIERARCHY of ROOT/JOINT/End Site blocks with OFFSETs and
// CHANNELS, then MOTION with one line of channel values per frame. Errors throw LoadError (io/load_error.h) as
// "FILE:LINE: message"; nothing half-loaded is ever returned.
//
// Conventions of the returned data (the usual BVH reading, which the CMU/Daz files follow):
//   * a joint's local rotation is the product of its rotation channels in the order they are listed, angles in
//     degrees, column vectors: "Zrotation Xrotation Yrotation" gives Rz * Rx * Ry;
//   * a joint's local translation is its OFFSET plus its position channels (in practice only the root has
//     position channels, and its OFFSET is zero, so the root's channels are its absolute position);
//   * the rest pose is every channel zero, so rest global rotations are identity and rest positions are the
//     summed OFFSETs.
// The file's units and axes are kept as they are; motion/retarget.h converts to H-Anim.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "io/load_error.h"

namespace strata {

enum class BvhChannel : std::uint8_t { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };
const char* to_string(BvhChannel channel);

struct BvhJoint {
  std::string name;
  std::int32_t parent = -1;           // index into BvhMotion::joints; -1 for the root
  glm::vec3 offset{0.0f};             // from the parent's origin, parent's rest axes, file units
  std::vector<BvhChannel> channels;   // in file order
  std::uint32_t first_channel = 0;    // column of channels[0] within a frame
  bool has_end_site = false;
  glm::vec3 end_site{0.0f};           // OFFSET of the End Site block, when has_end_site
};

struct BvhMotion {
  std::string source;                 // file name (or the name given to load_bvh_text)
  std::vector<BvhJoint> joints;       // file order, which is topological: parents[j] < j
  std::size_t channel_count = 0;      // values per frame (sum of every joint's CHANNELS count)
  float frame_time = 0.0f;            // seconds per frame
  std::size_t frame_count = 0;
  std::vector<float> values;          // frame_count * channel_count, frame-major

  std::size_t joint_count() const { return joints.size(); }
  std::size_t end_site_count() const;
  float duration() const { return frame_count > 1 ? static_cast<float>(frame_count - 1) * frame_time : 0.0f; }
  // Index of a joint by exact name; -1 when absent.
  std::int32_t find_joint(std::string_view name) const;
  std::span<const float> frame(std::size_t f) const { return {values.data() + f * channel_count, channel_count}; }

  // Joint j's local rotation at frame f (product of its rotation channels in listed order).
  glm::quat local_rotation(std::size_t joint, std::size_t f) const;
  glm::mat3 local_rotation_matrix(std::size_t joint, std::size_t f) const;
  // Joint j's local translation at frame f: OFFSET + position channels.
  glm::vec3 local_translation(std::size_t joint, std::size_t f) const;
  // The root's position channels at frame f (x, y, z; a missing channel reads 0).
  glm::vec3 root_translation(std::size_t f) const;
  // Global rest positions of every joint (summed OFFSETs, the root at its OFFSET).
  std::vector<glm::vec3> rest_positions() const;
  // Global rotations and positions of every joint at frame f, in file axes and units. Spans are joint_count() long.
  void pose(std::size_t f, std::span<glm::quat> global_rotations, std::span<glm::vec3> global_positions) const;
};

// Reads a .bvh file (LF or CRLF line ends, tabs or spaces).
BvhMotion load_bvh_file(const std::filesystem::path& path);
// Reads BVH text from memory; `source_name` is used in error messages and BvhMotion::source.
BvhMotion load_bvh_text(std::string_view text, std::string_view source_name);

}  // namespace strata
