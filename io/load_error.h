#pragma once
// LoadError: the one exception every loader throws. Its message is a single line that names the file, the line
// and the element at fault, e.g. "Joe.x3d:120: <HAnimJoint DEF='J_l_knee'>: center has 2 numbers, expected 3".
// Loaders build into locals and only return a complete result, so a throw never leaves anything half-loaded.
#include <stdexcept>
#include <string>

namespace strata {

class LoadError : public std::runtime_error {
 public:
  explicit LoadError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace strata
