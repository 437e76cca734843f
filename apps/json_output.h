#pragma once
// Writing the JSON every command and report produces: pretty-printed, written to a temporary sibling and renamed
// into place (io/atomic_file.h), and a failure names the path.
#include <filesystem>

#include <nlohmann/json.hpp>

#include "io/atomic_file.h"

namespace strata::cli {

inline void write_json_file(const std::filesystem::path& path, const nlohmann::json& value) {
  write_file_atomically(path, value.dump(2) + "\n");
}

}  // namespace strata::cli
