#pragma once
// Files from data/ and the renderer's shaders (render/shaders/) compiled into the library, so Strata runs with no
// external files (the list: STRATA_EMBEDDED_FILES in CMakeLists.txt; the generator: cmake/EmbedFiles.cmake).
#include <optional>
#include <string_view>

namespace strata::embedded {
// Bytes of a shipped file by its path relative to the source root, e.g. "data/default_skeleton.x3d" or
// "render/shaders/body.vert".
std::optional<std::string_view> find(std::string_view name);
}  // namespace strata::embedded
