#include "io/xml_util.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "io/load_error.h"

namespace strata::xml {
namespace {

bool is_separator(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == ','; }

// Splits on separators and hands each token to `parse_one`; stops at the first token it rejects.
template <typename ParseOne>
bool for_each_token(std::string_view text, std::string* error, ParseOne&& parse_one) {
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && is_separator(text[i])) ++i;
    if (i == text.size()) break;
    std::size_t end = i;
    while (end < text.size() && !is_separator(text[end])) ++end;
    const std::string_view token = text.substr(i, end - i);
    if (!parse_one(token)) {
      if (error) {
        // Appended piecewise: GCC 12 warns (-Wrestrict, a known false positive) on "'" + std::string(...).
        error->assign(1, '\'');
        error->append(token);
        error->append("' is not a valid number");
      }
      return false;
    }
    i = end;
  }
  return true;
}

// from_chars rejects a leading '+', which hand-written X3D does contain now and then.
std::string_view strip_plus(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  return token;
}

}  // namespace

Document::Document(std::string_view text, std::string_view source_name) : source_name_(source_name) {
  line_starts_.push_back(0);
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') line_starts_.push_back(i + 1);

  // load_buffer copies the text, and offset_debug() then reports offsets into that copy, which for UTF-8 input
  // equal offsets into `text` (the only encoding X3D files use in practice).
  const pugi::xml_parse_result result =
      doc_.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!result) {
    // pugixml knows no element at this point, so quote the text where it stopped instead.
    std::string near;
    if (result.offset >= 0 && static_cast<std::size_t>(result.offset) < text.size()) {
      std::string_view rest = text.substr(static_cast<std::size_t>(result.offset), 32);
      rest = rest.substr(0, rest.find_first_of("\r\n"));
      if (!rest.empty()) near = " near '" + std::string(rest) + "'";
    }
    throw LoadError(source_name_ + ":" + std::to_string(line_of_offset(result.offset)) +
                    ": malformed XML: " + result.description() + near);
  }
  // The readers walk the element tree recursively; a hostile file nested tens of thousands deep would overflow
  // the stack (found by fuzzing). Real humanoids nest a few dozen levels (Joe: 34), so the walk below, iterative,
  // refuses anything deeper than kMaxDepth instead of making every reader iterative.
  constexpr int kMaxDepth = 256;
  int depth = 0;
  for (pugi::xml_node n = doc_.first_child(); n;) {
    if (n.first_child()) {
      n = n.first_child();
      if (++depth > kMaxDepth)
        throw LoadError(where(n.parent()) + ": elements nested deeper than " + std::to_string(kMaxDepth) + " levels");
      continue;
    }
    while (n && !n.next_sibling()) {
      n = n.parent();
      --depth;
    }
    if (n) n = n.next_sibling();
  }
}

int Document::line_of_offset(std::ptrdiff_t offset) const {
  if (offset < 0) return 0;
  const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), static_cast<std::size_t>(offset));
  return static_cast<int>(it - line_starts_.begin());
}

int Document::line_of(pugi::xml_node node) const { return line_of_offset(node.offset_debug()); }

std::string Document::where(pugi::xml_node node) const {
  return source_name_ + ":" + std::to_string(line_of(node)) + ": " + element_label(node);
}

void Document::fail(pugi::xml_node node, std::string_view message) const {
  throw LoadError(where(node) + ": " + std::string(message));
}

std::string Document::warning(pugi::xml_node node, std::string_view message) const {
  return where(node) + ": " + std::string(message);
}

std::string element_label(pugi::xml_node node) {
  std::string label = "<";
  label += node.name();
  for (const char* key : {"DEF", "USE", "name"}) {
    const pugi::xml_attribute a = node.attribute(key);
    if (a) {
      label += ' ';
      label += key;
      label += "='";
      label += a.value();
      label += '\'';
    }
  }
  label += '>';
  return label;
}

bool parse_floats(std::string_view text, std::vector<float>& out, std::string* error) {
  out.clear();
  return for_each_token(text, error, [&](std::string_view token) {
    token = strip_plus(token);
    float value = 0.0f;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size() || !std::isfinite(value)) return false;
    out.push_back(value);
    return true;
  });
}

bool parse_ints(std::string_view text, std::vector<std::int64_t>& out, std::string* error) {
  out.clear();
  return for_each_token(text, error, [&](std::string_view token) {
    token = strip_plus(token);
    std::int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size()) return false;
    out.push_back(value);
    return true;
  });
}

std::optional<std::vector<float>> float_list_attr(const Document& doc, pugi::xml_node node, const char* attr) {
  const pugi::xml_attribute a = node.attribute(attr);
  if (!a) return std::nullopt;
  std::vector<float> values;
  std::string error;
  if (!parse_floats(a.value(), values, &error)) doc.fail(node, std::string(attr) + ": " + error);
  return values;
}

std::optional<std::vector<std::int64_t>> int_list_attr(const Document& doc, pugi::xml_node node,
                                                       const char* attr) {
  const pugi::xml_attribute a = node.attribute(attr);
  if (!a) return std::nullopt;
  std::vector<std::int64_t> values;
  std::string error;
  if (!parse_ints(a.value(), values, &error)) doc.fail(node, std::string(attr) + ": " + error);
  return values;
}

std::optional<std::vector<float>> fixed_floats_attr(const Document& doc, pugi::xml_node node, const char* attr,
                                                    std::size_t count) {
  auto values = float_list_attr(doc, node, attr);
  if (values && values->size() != count) {
    doc.fail(node, std::string(attr) + " has " + std::to_string(values->size()) + " numbers, expected " +
                       std::to_string(count));
  }
  return values;
}

std::optional<glm::vec3> vec3_attr(const Document& doc, pugi::xml_node node, const char* attr) {
  const auto values = fixed_floats_attr(doc, node, attr, 3);
  if (!values) return std::nullopt;
  return glm::vec3((*values)[0], (*values)[1], (*values)[2]);
}

std::optional<float> float_attr(const Document& doc, pugi::xml_node node, const char* attr) {
  const auto values = fixed_floats_attr(doc, node, attr, 1);
  if (!values) return std::nullopt;
  return (*values)[0];
}

std::optional<bool> bool_attr(const Document& doc, pugi::xml_node node, const char* attr) {
  const pugi::xml_attribute a = node.attribute(attr);
  if (!a) return std::nullopt;
  const std::string_view v = a.value();
  if (v == "true" || v == "TRUE") return true;
  if (v == "false" || v == "FALSE") return false;
  doc.fail(node, std::string(attr) + ": '" + std::string(v) + "' is not true or false");
}

}  // namespace strata::xml
