#pragma once
// The skeleton pass: every bone of every walker as a lit tapered prism and every joint as a small lit sphere, in
// two instanced draws (one for all bones, one for all joints). Drawn inside the bodies when both are on; on its
// own it is the crowd at level -1 and the debugging view of a rig.
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "render/gl_program.h"
#include "render/render_options.h"
#include "render/skeleton_geometry.h"
#include "render/skeleton_input.h"

namespace strata {

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
