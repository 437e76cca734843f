#pragma once
// The input formats, in one table: which files Strata reads, what each can give a crowd (a skeleton, a skinned
// body, motion, a bare mesh), and how a path is recognised. `strata info` and build_scene (so crowd, view, bench,
// soak and the reports) all identify their inputs here, so a format is added in one place: a row in
// input_formats.cpp, its loader in io/, and the branch that turns its result into a rig (load_mesh_rig in
// scene_setup.cpp) or a summary (apps/cmd_info.cpp).
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace strata {

enum class InputFormatId : std::uint8_t { HAnim, Bvh, Obj, Gltf, MakeHuman };

// What a format can give a crowd (a bit set).
enum InputUse : std::uint8_t {
  kGivesSkeleton = 1,     // --skeleton: an H-Anim humanoid
  kGivesSkinnedBody = 2,  // --mesh: a skinned body with its skeleton (and clips)
  kGivesMotion = 4,       // --motion: motion capture retargeted onto the rig
  kGivesMesh = 8,         // a bare mesh (info only)
};

struct InputFormat {
  InputFormatId id;
  std::string_view name;                     // short, for messages: "H-Anim", "BVH", ...
  std::string_view description;              // for help and info
  std::span<const std::string_view> extensions;  // lower case, with the dot; matched case-insensitively
  bool directory = false;                    // a folder of files rather than one file
  std::uint8_t gives = 0;                    // InputUse bits
  std::string_view gives_note;               // when a use depends on the file's content (an X3D skin), why
};

// Every format, in the order help text lists them.
std::span<const InputFormat> input_formats();
// The format of `path`: a directory is a MakeHuman folder, a file goes by its extension (case-insensitive).
// Throws LoadError "PATH: not a supported input (...)" naming the supported extensions.
const InputFormat& identify_input(const std::filesystem::path& path);
// Checks that `path` can serve as `use` (one InputUse bit) for the flag `flag` ("--mesh"), and returns its
// format; throws LoadError naming the flag, the file's format and the formats that can, e.g.
// "--mesh: walk.bvh is BVH motion capture, which has no skinned body (use .glb/.gltf, a MakeHuman folder, .x3d)".
const InputFormat& require_input(const std::filesystem::path& path, InputUse use, std::string_view flag);
// "a.x3d, .xml" style list of the formats that give `use`.
std::string formats_giving(InputUse use);

}  // namespace strata
