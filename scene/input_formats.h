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

// The largest input file read without asking (1 GiB): above it a path is refused before a loader reads it, so
// `strata info` on something huge (or endless: a device) answers at once. Commands raise it with
// --max-input-mb (apps/scene_options.cpp). Process-wide rather than a parameter of every loader call: the limit
// is a property of the run, and threading it through each loader signature was rejected as churn in io/.
inline constexpr std::uint64_t kDefaultInputSizeLimit = std::uint64_t{1} << 30;
void set_input_size_limit(std::uint64_t bytes);
std::uint64_t input_size_limit();

// Checks that an existing `path` can be read as an input: a regular file no larger than input_size_limit(), or
// (with `directory_ok`) a directory. Refuses FIFOs, devices and sockets (reading them blocks or never ends), symbolic
// link loops and oversized files with a LoadError naming the path. A path that does not exist passes: the loader
// then says so with its own message.
void check_input_path(const std::filesystem::path& path, bool directory_ok = true);

// Every format, in the order help text lists them.
std::span<const InputFormat> input_formats();
// The format of `path`: a directory is a MakeHuman folder; an existing file is first checked
// (check_input_path), then recognised by its first bytes when they are unmistakable (the GLB magic, BVH's
// HIERARCHY, an XML '<', glTF JSON with "asset", OBJ statements), which win over the extension, so a renamed
// or mislabelled file is read as what it is; otherwise, and for paths that do not exist, by the extension
// (case-insensitive). Throws LoadError "PATH: not a supported input (...)" naming the supported extensions.
const InputFormat& identify_input(const std::filesystem::path& path);
// Checks that `path` can serve as `use` (one InputUse bit) for the flag `flag` ("--mesh"), and returns its
// format; throws LoadError naming the flag, the file's format and the formats that can, e.g.
// "--mesh: walk.bvh is BVH motion capture, which has no skinned body (use .glb/.gltf, a MakeHuman folder, .x3d)".
const InputFormat& require_input(const std::filesystem::path& path, InputUse use, std::string_view flag);
// "a.x3d, .xml" style list of the formats that give `use`.
std::string formats_giving(InputUse use);

}  // namespace strata
