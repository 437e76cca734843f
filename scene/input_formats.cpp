#include "scene/input_formats.h"

#include <algorithm>
#include <array>
#include <cctype>

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

}  // namespace

std::span<const InputFormat> input_formats() { return kFormats; }

const InputFormat& identify_input(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    for (const InputFormat& f : kFormats)
      if (f.directory) return f;
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
