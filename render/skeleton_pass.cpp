// Instanced skeleton drawing (GL 4.5 core, direct state access throughout).
//
// Per-instance data is re-specified every frame with glNamedBufferData (buffer orphaning). Persistent mapping
// was the alternative; it needs a ring of regions and fences to avoid overwriting data an in-flight draw still
// reads, and it only pays off for uploads far larger than ours (1,000 walkers x ~70 bones x 48 B is ~3 MB,
// a memcpy on llvmpipe). Orphaning gives the same no-stall behaviour with the driver doing the bookkeeping.
#include "render/skeleton_pass.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace strata {

namespace {

bool is_finite_joint(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

SkeletonPass::SkeletonPass()
    : program_(link_program("render/shaders/skeleton.vert", "render/shaders/lit.frag")),
      bone_(upload(make_bone_mesh())),
      joint_(upload(make_sphere_mesh())) {}

SkeletonPass::InstancedMesh SkeletonPass::upload(const UnitMesh& mesh) {
  InstancedMesh gpu;
  gpu.index_count = static_cast<int>(mesh.indices.size());
  gpu.vertex_buffer = GlObject(GlKind::kBuffer);
  glNamedBufferStorage(gpu.vertex_buffer.id(), static_cast<GLsizeiptr>(mesh.vertices.size() * sizeof(MeshVertex)),
                       mesh.vertices.data(), 0);
  gpu.index_buffer = GlObject(GlKind::kBuffer);
  glNamedBufferStorage(gpu.index_buffer.id(), static_cast<GLsizeiptr>(mesh.indices.size() * sizeof(std::uint16_t)),
                       mesh.indices.data(), 0);
  gpu.instance_buffer = GlObject(GlKind::kBuffer);  // storage is (re)specified per frame

  gpu.vao = GlObject(GlKind::kVertexArray);
  const GLuint vao = gpu.vao.id();
  glVertexArrayVertexBuffer(vao, 0, gpu.vertex_buffer.id(), 0, sizeof(MeshVertex));
  glVertexArrayVertexBuffer(vao, 1, gpu.instance_buffer.id(), 0, sizeof(InstanceRows));
  glVertexArrayBindingDivisor(vao, 1, 1);
  glVertexArrayElementBuffer(vao, gpu.index_buffer.id());
  auto attribute = [&](GLuint location, GLuint binding, GLint size, GLuint offset) {
    glEnableVertexArrayAttrib(vao, location);
    glVertexArrayAttribFormat(vao, location, size, GL_FLOAT, GL_FALSE, offset);
    glVertexArrayAttribBinding(vao, location, binding);
  };
  attribute(0, 0, 3, offsetof(MeshVertex, position));
  attribute(1, 0, 3, offsetof(MeshVertex, normal));
  for (GLuint i = 0; i < 3; ++i) attribute(2 + i, 1, 4, static_cast<GLuint>(i * sizeof(glm::vec4)));
  return gpu;
}

void SkeletonPass::draw(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
                        const RenderOptions& options) {
  build_instances(input, options);
  const GLuint p = program_.id();
  glUseProgram(p);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  const GLint color_location = glGetUniformLocation(p, "u_color");
  draw_instances(bone_, bone_instances_, options.bone_color, color_location);
  draw_instances(joint_, joint_instances_, options.joint_color, color_location);
}

void SkeletonPass::draw_instances(const InstancedMesh& mesh, const std::vector<InstanceRows>& instances,
                                  const glm::vec3& color, int color_location) const {
  if (instances.empty()) return;
  glNamedBufferData(mesh.instance_buffer.id(), static_cast<GLsizeiptr>(instances.size() * sizeof(InstanceRows)),
                    instances.data(), GL_STREAM_DRAW);
  glProgramUniform3fv(program_.id(), color_location, 1, glm::value_ptr(color));
  glBindVertexArray(mesh.vao.id());
  glDrawElementsInstanced(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_SHORT, nullptr,
                          static_cast<GLsizei>(instances.size()));
}

void SkeletonPass::build_instances(const SkeletonDrawInput& input, const RenderOptions& options) {
  bone_instances_.clear();
  joint_instances_.clear();
  if (input.walker_count == 0) return;
  const auto to_rows = [](const glm::mat4& m) {
    InstanceRows r;
    for (int i = 0; i < 3; ++i) r.row[i] = glm::vec4{m[0][i], m[1][i], m[2][i], m[3][i]};
    return r;
  };
  const Skeleton& skeleton = *input.skeleton;
  const std::size_t joints = skeleton.joint_count();
  size_radii(skeleton, options);
  for (std::size_t w = 0; w < input.walker_count; ++w) {
    const glm::vec3* pose = input.joint_positions.data() + w * joints;
    for (std::size_t j = 0; j < joints; ++j) {
      if (!is_finite_joint(pose[j])) continue;
      glm::mat4 m = glm::mat4(joint_radii_[j]);
      m[3] = glm::vec4(pose[j], 1.0f);
      joint_instances_.push_back(to_rows(m));
      const std::int32_t parent = skeleton.parents[j];
      if (parent < 0) continue;
      if (auto bone_m = bone_transform(pose[parent], pose[j], bone_radii_[j]))
        bone_instances_.push_back(to_rows(*bone_m));
    }
  }
}

// Joint and bone thickness per joint, from the rest skeleton: the configured radii, shrunk where bones are
// short, so an 89-joint H-Anim hand reads as fingers rather than a ball of spheres. Bone j is parent -> j.
void SkeletonPass::size_radii(const Skeleton& skeleton, const RenderOptions& options) {
  const std::size_t joints = skeleton.joint_count();
  std::vector<float> shortest(joints, std::numeric_limits<float>::max());
  for (std::size_t j = 0; j < joints; ++j) {
    const std::int32_t parent = skeleton.parents[j];
    if (parent < 0) continue;
    const float length = glm::length(skeleton.centers[j] - skeleton.centers[parent]);
    if (!(length > 1e-6f)) continue;
    shortest[j] = std::min(shortest[j], length);
    shortest[parent] = std::min(shortest[parent], length);
  }
  joint_radii_.resize(joints);
  bone_radii_.resize(joints);
  for (std::size_t j = 0; j < joints; ++j) {
    const float limit = shortest[j] == std::numeric_limits<float>::max() ? options.joint_radius : shortest[j];
    joint_radii_[j] = std::min(options.joint_radius, 0.3f * limit);
    bone_radii_[j] = std::min(options.bone_radius, 0.25f * limit);
  }
}

}  // namespace strata
