#pragma once
// The skeleton pass: every bone of every walker as a lit tapered prism and every joint as a small lit sphere, in
// two instanced draws (one for all bones, one for all joints). Drawn inside the bodies when both are on; on its
// own it is the crowd at level -1 and the debugging view of a rig.
#include <cstddef>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "components/skeleton.h"
#include "render/gl_program.h"
#include "render/render_options.h"
#include "render/skeleton_geometry.h"

namespace strata {

struct SkeletonDrawInput {
  const Skeleton* skeleton = nullptr;
  // World-space joint positions, walker-major: joint j of walker w at [w * joint_count + j].
  std::span<const glm::vec3> joint_positions;
  std::size_t walker_count = 0;
};

// Throws std::invalid_argument when `input` has walkers but no skeleton, a skeleton whose parents disagree with
// its joint count, or fewer joint positions than walkers x joints. Every pass that reads the joints relies on it.
void check_skeleton_input(const SkeletonDrawInput& input);

// The joint positions an input really holds: walker_count x joint_count of them (none without a skeleton).
std::span<const glm::vec3> drawn_joint_positions(const SkeletonDrawInput& input);

class SkeletonPass {
 public:
  // Needs a current GL 4.5 core context (as do draw and the destructor). Throws std::runtime_error on a shader
  // failure.
  SkeletonPass();

  // Draws the bones and joints of `input` (checked by check_skeleton_input) into the bound framebuffer, sized by
  // options.bone_radius / joint_radius and coloured by options.bone_color / joint_color.
  void draw(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
            const RenderOptions& options);

 private:
  // Rows of the affine part of an instance transform: what skeleton.vert reads per instance (48 B, not a mat4's
  // 64 B: the last row is always 0 0 0 1).
  struct InstanceRows {
    glm::vec4 row[3];
  };
  // A unit mesh on the GPU with its per-instance buffer, re-specified every frame.
  struct InstancedMesh {
    GlObject vao, vertex_buffer, index_buffer, instance_buffer;
    int index_count = 0;
  };
  static InstancedMesh upload(const UnitMesh& mesh);
  void build_instances(const SkeletonDrawInput& input, const RenderOptions& options);
  void size_radii(const Skeleton& skeleton, const RenderOptions& options);
  void draw_instances(const InstancedMesh& mesh, const std::vector<InstanceRows>& instances, const glm::vec3& color,
                      int color_location) const;

  GlObject program_;
  InstancedMesh bone_, joint_;
  // Kept between frames so steady-state rendering does not allocate.
  std::vector<InstanceRows> bone_instances_, joint_instances_;
  std::vector<float> joint_radii_, bone_radii_;  // per joint, see size_radii
};

}  // namespace strata
