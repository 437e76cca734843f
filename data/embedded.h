#pragma once
// Files from data/ compiled into the library, so Strata runs with no external data (see cmake/EmbedFiles.cmake).
#include <optional>
#include <string_view>

namespace strata::embedded {
// Bytes of a shipped file by its path relative to the source root, e.g. "data/default_skeleton.x3d".
std::optional<std::string_view> find(std::string_view name);
}  // namespace strata::embedded
