#include "render/topology_buffer.h"

#include <epoxy/gl.h>

#include <meshoptimizer.h>

namespace strata {

void TopologyBuffer::upload(std::span<const std::uint32_t> triangles, std::size_t vertex_count,
                            std::vector<std::uint32_t>& scratch) {
  scratch.resize(triangles.size());
  meshopt_optimizeVertexCache(scratch.data(), triangles.data(), triangles.size(), vertex_count);
  glNamedBufferData(buffer_.id(), static_cast<GLsizeiptr>(scratch.size() * sizeof(std::uint32_t)), scratch.data(),
                    GL_STATIC_DRAW);
  topology_ = triangles.data();
  index_count_ = triangles.size();
  vertex_count_ = vertex_count;
}

}  // namespace strata
