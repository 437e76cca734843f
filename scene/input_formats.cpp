#include "scene/input_formats.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cerrno>
#include <fstream>
#include <system_error>

#include "io/load_error.h"

namespace strata {
namespace {

constexpr std::string_view kHAnimExt[] = {".x3d", ".xml"};
constexpr std::string_view kBvhExt[] = {".bvh"};
constexpr std::string_view kObjExt[] = {".obj"};
constexpr std::string_view kGltfExt[] = {".glb", ".gltf"};

const std::array<InputFormat, 5> kFormats{{
    {InputFormatId::HAnim, "H-Anim", "H-Anim 1.1 humanoid: X3D encoding or the paper's simple XML", kHAnimExt, false,
     kGivesSkeleton | kGivesSkinnedBody, "a skinned body only when the X3D file has a skin with weights"},
    {InputFormatId::Bvh, "BVH", "BVH motion capture", kBvhExt, false, kGivesMotion, ""},
    {InputFormatId::Obj, "OBJ", "Wavefront OBJ mesh (no skeleton)", kObjExt, false, kGivesMesh, ""},
    {InputFormatId::Gltf, "glTF", "glTF 2.0 skinned body with its animation (.glb or .gltf)", kGltfExt, false,
     kGivesSkinnedBody, ""},
    {InputFormatId::MakeHuman, "MakeHuman", "MakeHuman hm08 folder (base.obj, default.mhskel, default_weights.mhw)",
     {}, true, kGivesSkinnedBody, ""},
}};

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string all_extensions() {
  std::string out;
  for (const InputFormat& f : kFormats) {
    for (std::string_view e : f.extensions) out += (out.empty() ? "" : ", ") + std::string(e);
    if (f.directory) out += (out.empty() ? "" : ", ") + std::string("a ") + std::string(f.name) + " folder";
  }
  return out;
}

std::atomic<std::uint64_t> g_size_limit{kDefaultInputSizeLimit};

const InputFormat& format_of(InputFormatId id) {
  for (const InputFormat& f : kFormats)
    if (f.id == id) return f;
  return kFormats.front();
}

// The format the first bytes of a regular file show, or nullptr when they do not say. Only signatures no other
// supported format can start with count; anything else falls back to the extension.
const InputFormat* sniff(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  char buffer[4096];
  in.read(buffer, sizeof buffer);
  std::string head(buffer, static_cast<std::size_t>(in.gcount()));
  if (head.rfind("glTF", 0) == 0) return &format_of(InputFormatId::Gltf);
  std::size_t at = head.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;  // a UTF-8 byte order mark
  auto skip_space = [&] {
    while (at < head.size() && std::isspace(static_cast<unsigned char>(head[at]))) ++at;
  };
  skip_space();
  if (head.compare(at, 9, "HIERARCHY") == 0) return &format_of(InputFormatId::Bvh);
  if (at < head.size() && head[at] == '<') return &format_of(InputFormatId::HAnim);
  if (at < head.size() && head[at] == '{')
    return head.find("\"asset\"") != std::string::npos ? &format_of(InputFormatId::Gltf) : nullptr;
  // OBJ: comments, then a statement keyword. '#' alone says nothing (BVH and X3D cannot start with it, but a
  // text file can), so the first statement decides.
  while (at < head.size()) {
    if (head[at] == '#') {
      const std::size_t eol = head.find('\n', at);
      if (eol == std::string::npos) return nullptr;
      at = eol + 1;
      skip_space();
      continue;
    }
    for (const char* keyword : {"v ", "vn ", "vt ", "f ", "o ", "g ", "s ", "mtllib ", "usemtl "})
      if (head.compare(at, std::char_traits<char>::length(keyword), keyword) == 0)
        return &format_of(InputFormatId::Obj);
    return nullptr;
  }
  return nullptr;
}

std::string size_text(std::uint64_t bytes) {
  char text[32];
  if (bytes >= (std::uint64_t{1} << 30))
    std::snprintf(text, sizeof text, "%.1f GiB", static_cast<double>(bytes) / double(std::uint64_t{1} << 30));
  else
    std::snprintf(text, sizeof text, "%.1f MiB", static_cast<double>(bytes) / double(std::uint64_t{1} << 20));
  return text;
}

}  // namespace

std::span<const InputFormat> input_formats() { return kFormats; }

void set_input_size_limit(std::uint64_t bytes) { g_size_limit.store(bytes); }
std::uint64_t input_size_limit() { return g_size_limit.load(); }

void check_input_path(const std::filesystem::path& path, bool directory_ok) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(path, ec))) return;  // the loader names the missing file
  const fs::file_status status = fs::status(path, ec);
  if (ec && ec.value() == ELOOP) throw LoadError(path.string() + ": symbolic link loop");
  if (ec || !fs::exists(status)) {
    if (fs::is_symlink(fs::symlink_status(path, ec))) throw LoadError(path.string() + ": broken symbolic link");
    return;
  }
  if (fs::is_directory(status)) {
    if (directory_ok) return;
    throw LoadError(path.string() + ": is a directory, expected a file");
  }
  const char* kind = fs::is_fifo(status)               ? "a FIFO"
                     : fs::is_character_file(status) ? "a character device"
                     : fs::is_block_file(status)     ? "a block device"
                     : fs::is_socket(status)         ? "a socket"
                     : fs::is_regular_file(status)   ? nullptr
                                                     : "not a file";
  if (kind) throw LoadError(path.string() + ": not a regular file (" + kind + ")");
  const std::uint64_t size = fs::file_size(path, ec);
  if (!ec && size > input_size_limit())
    throw LoadError(path.string() + ": " + size_text(size) + " is above the input size limit of " +
                    size_text(input_size_limit()) + " (raise it with --max-input-mb)");
}

const InputFormat& identify_input(const std::filesystem::path& path) {
  check_input_path(path);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    // Every directory format so far is MakeHuman's, which always has base.obj; any other folder is refused here
    // rather than by the loader's "base.obj: cannot open file", which does not say the folder was the problem.
    if (!std::filesystem::exists(path / "base.obj", ec))
      throw LoadError(path.string() + ": a directory, and not a MakeHuman hm08 folder (no base.obj)");
    for (const InputFormat& f : kFormats)
      if (f.directory) return f;
  }
  if (std::filesystem::is_regular_file(path, ec))
    if (const InputFormat* sniffed = sniff(path)) return *sniffed;
  const std::string ext = lower(path.extension().string());
  for (const InputFormat& f : kFormats)
    if (std::find(f.extensions.begin(), f.extensions.end(), ext) != f.extensions.end()) return f;
  throw LoadError(path.string() + ": not a supported input (" + all_extensions() + ")");
}

std::string formats_giving(InputUse use) {
  std::string out;
  for (const InputFormat& f : kFormats) {
    if (!(f.gives & use)) continue;
    for (std::string_view e : f.extensions) out += (out.empty() ? "" : ", ") + std::string(e);
    if (f.directory) out += (out.empty() ? "" : ", ") + std::string("a ") + std::string(f.name) + " folder";
  }
  return out;
}

const InputFormat& require_input(const std::filesystem::path& path, InputUse use, std::string_view flag) {
  const InputFormat* format = nullptr;
  try {
    format = &identify_input(path);
  } catch (const LoadError& e) {
    throw LoadError(std::string(flag) + ": " + e.what());
  }
  if (!(format->gives & use)) {
    const char* what = use == kGivesSkeleton ? "no H-Anim skeleton"
                       : use == kGivesSkinnedBody ? "no skinned body"
                       : use == kGivesMotion ? "no motion"
                                             : "no mesh";
    throw LoadError(std::string(flag) + ": " + path.string() + " is " + std::string(format->description) +
                    ", which has " + what + " (use " + formats_giving(use) + ")");
  }
  return *format;
}

}  // namespace strata
