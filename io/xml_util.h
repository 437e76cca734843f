#pragma once
// Helpers over pugixml shared by the H-Anim readers: a parsed document that remembers where each element came
// from (file and line), strict number-list parsing, and the one-line error format of io/load_error.h:
//   "FILE:LINE: <Element DEF='x' name='y'>: message".
// Private to the library (not installed as API any consumer should rely on).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>
#include <pugixml.hpp>

namespace strata::xml {

// A parsed XML text plus what is needed to turn pugixml's byte offsets back into line numbers.
class Document {
 public:
  // Parses `text`; throws LoadError "SOURCE:LINE: malformed XML: <pugixml's description>" on failure.
  Document(std::string_view text, std::string_view source_name);
  Document(const Document&) = delete;
  Document& operator=(const Document&) = delete;

  pugi::xml_node root() const { return doc_.document_element(); }
  const std::string& source_name() const { return source_name_; }

  // 1-based line of an element's start tag (0 when pugixml cannot say).
  int line_of(pugi::xml_node node) const;
  int line_of_offset(std::ptrdiff_t offset) const;

  // "SOURCE:LINE: <Tag DEF='..' name='..'>" for messages and warnings.
  std::string where(pugi::xml_node node) const;
  // Throws LoadError with where(node) + ": " + message.
  [[noreturn]] void fail(pugi::xml_node node, std::string_view message) const;
  // where(node) + ": " + message, for Skeleton::warnings.
  std::string warning(pugi::xml_node node, std::string_view message) const;

 private:
  pugi::xml_document doc_;
  std::string source_name_;
  std::vector<std::size_t> line_starts_;  // byte offset of the first character of each line
};

// "<Tag DEF='x' name='y'>", or "<Tag USE='x'>"; only the identifying attributes that are present.
std::string element_label(pugi::xml_node node);

// Parses numbers separated by any mix of whitespace and commas (X3D's MF field syntax). Strict: every token must
// be a complete finite number, so "0.1 abc", "1.5x" and "nan" fail. On failure returns false and sets *error.
bool parse_floats(std::string_view text, std::vector<float>& out, std::string* error);
// Same, for integers (X3D MFInt32); "1.5" is rejected rather than truncated.
bool parse_ints(std::string_view text, std::vector<std::int64_t>& out, std::string* error);

// Typed attribute readers that throw doc.fail(node, "<attr>: <reason>") on a bad value.
// Absent attribute -> nullopt (the caller decides whether that is an error or means a default).
std::optional<std::vector<float>> float_list_attr(const Document& doc, pugi::xml_node node, const char* attr);
std::optional<std::vector<std::int64_t>> int_list_attr(const Document& doc, pugi::xml_node node, const char* attr);
// Exactly `count` numbers; absent -> nullopt.
std::optional<std::vector<float>> fixed_floats_attr(const Document& doc, pugi::xml_node node, const char* attr,
                                                    std::size_t count);
std::optional<glm::vec3> vec3_attr(const Document& doc, pugi::xml_node node, const char* attr);
std::optional<float> float_attr(const Document& doc, pugi::xml_node node, const char* attr);

// X3D SFBool as written in XML encodings ("true"/"false"; VRML-style "TRUE"/"FALSE" accepted too).
std::optional<bool> bool_attr(const Document& doc, pugi::xml_node node, const char* attr);

}  // namespace strata::xml
