#pragma once
// LoadError: the one exception every loader throws. Its message is a single line that names the file, the line
// and the element at fault, e.g. "Joe.x3d:120: <HAnimJoint DEF='J_l_knee'>: center has 2 numbers, expected 3".
// Loaders build into locals and only return a complete result, so a throw never leaves anything half-loaded.
//
// The message quotes names from the file, and a file can put anything in a name: a JSON "\n" escape, a newline
// inside an XML attribute. The constructor therefore writes control characters as escapes (\n, \r, \xNN), so the
// one-line promise holds whatever the input (fuzz_binding found a joint name with a newline). Escaping at each
// quoting site was rejected: there are dozens, and one forgotten site breaks the contract.
#include <cstdio>
#include <stdexcept>
#include <string>

namespace strata {

class LoadError : public std::runtime_error {
 public:
  explicit LoadError(const std::string& message) : std::runtime_error(one_line(message)) {}

  static std::string one_line(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
      const auto byte = static_cast<unsigned char>(c);
      if (c == '\n') {
        out += "\\n";
      } else if (c == '\r') {
        out += "\\r";
      } else if (byte < 0x20 && c != '\t') {
        char escaped[8];
        std::snprintf(escaped, sizeof escaped, "\\x%02X", byte);
        out += escaped;
      } else {
        out += c;
      }
    }
    return out;
  }
};

}  // namespace strata
