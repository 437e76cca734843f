#pragma once
// An index buffer holding one triangle list, for the passes that draw bodies (body and reference). The list goes
// up reordered for the post-transform vertex cache (meshoptimizer), which the same triangles in a different order
// cost nothing to get, and only when it changes: a body level's topology is fixed, so after the first frame only
// vertices stream. A change is a different address, index count or vertex count; comparing the indices
// themselves every frame would cost as much as uploading them.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "render/gl_program.h"

namespace strata {

class TopologyBuffer {
 public:
  // Needs a current GL context (as do upload and the destructor).
  TopologyBuffer() : buffer_(GlKind::kBuffer) {}

  // Whether the buffer already holds `triangles` (by identity, see above) over `vertex_count` vertices.
  bool holds(std::span<const std::uint32_t> triangles, std::size_t vertex_count) const {
    return topology_ == triangles.data() && index_count_ == triangles.size() && vertex_count_ == vertex_count;
  }
  // Reorders `triangles` (indices below vertex_count, checked by the caller) into `scratch` and uploads them.
  void upload(std::span<const std::uint32_t> triangles, std::size_t vertex_count,
              std::vector<std::uint32_t>& scratch);
  unsigned id() const { return buffer_.id(); }

 private:
  GlObject buffer_;
  const std::uint32_t* topology_ = nullptr;
  std::size_t index_count_ = 0, vertex_count_ = 0;
};

}  // namespace strata
