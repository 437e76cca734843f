// strata info FILE: load any supported input and print a summary; non-zero exit with a one-line reason on bad input.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <set>

#include <filesystem>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/scene_options.h"
#include "scene/input_formats.h"
#include "scene/scene_setup.h"
#include "io/bvh.h"
#include "motion/bvh_naming.h"
#include "io/hanim_loader.h"
#include "io/obj.h"

namespace strata::cli {
namespace {

// A skinned mesh's rest height, its feet to the top of its head (the meshes are +Y up once loaded).
float mesh_height(const Mesh& m) {
  if (m.positions.empty()) return 0.0f;
  const auto [low, high] = std::minmax_element(m.positions.begin(), m.positions.end(),
                                               [](const glm::vec3& a, const glm::vec3& b) { return a.y < b.y; });
  return high->y - low->y;
}

// Meshes, skinned bodies and motion capture: the formats other than humanoid XML.
int run_other_info(const std::string& path, InputFormatId format) {
  try {
    if (format == InputFormatId::Bvh) {
      const BvhMotion m = load_bvh_file(path);
      std::cout << "file:       " << path << "\nformat:     BVH motion capture\njoints:     " << m.joint_count()
                << " (+" << m.end_site_count() << " end sites), " << m.channel_count << " channels\nframes:     "
                << m.frame_count << " at " << m.frame_time << " s (" << m.duration() << " s)\n";
      // The naming family and the map a retarget would use; a capture that is not a known humanoid still gets
      // its summary above, and the reason instead of a map.
      try {
        const BvhNaming n = recognise_bvh_naming(m);
        std::cout << "family:     " << n.family << "\nunits:      " << n.units;
        if (n.metres_per_unit > 0.0f) std::cout << "\njoint_height_m: " << n.stature * n.metres_per_unit;
        std::cout << "\nmap:        BVH joint -> H-Anim joint (aimed at)\n";
        for (const RetargetMapping& row : n.map) {
          std::cout << "  " << row.bvh << " -> " << row.hanim;
          if (!row.hanim_aim.empty())
            std::cout << " (" << (row.bvh_aim.empty() ? std::string("end") : row.bvh_aim) << " / " << row.hanim_aim
                      << ")";
          std::cout << "\n";
        }
      } catch (const std::invalid_argument& e) {
        std::cout << "family:     none (" << e.what() << ")\n";
      }
    } else if (format == InputFormatId::Obj) {
      const Mesh m = load_obj_file(path);
      std::cout << "file:       " << path << "\nformat:     Wavefront OBJ\nvertices:   " << m.vertex_count()
                << "\ntriangles:  " << m.triangle_count() << "\nparts:      " << m.part_names.size() << "\n";
    } else {
      const Rig rig = load_mesh_rig(path);
      const Mesh& m = rig.body->levels.front().mesh;
      std::cout << "file:       " << path << "\nformat:     "
                << (format == InputFormatId::Gltf ? "glTF 2.0 skinned mesh" : "MakeHuman hm08 body")
                << "\njoints:     " << rig.skeleton.joint_count() << "\nvertices:   " << m.vertex_count()
                << "\ntriangles:  " << m.triangle_count() << "\nparts:      " << m.part_names.size()
                << "\nstature_m:  " << mesh_height(m) << " (skin)"
                << "\nclips:      " << rig.clips.size() << "\n";
      for (const AnimationClip& c : rig.clips)
        std::cout << "  " << c.name << ": " << c.duration << " s, " << c.rotations.size() << " rotation + "
                  << c.translations.size() << " translation channels\n";
      for (const std::string& w : rig.skeleton.warnings) std::cout << "warning:    " << w << "\n";
    }
  } catch (const std::exception& e) {
    print_error("info", error_text(e));
    return 1;
  }
  return 0;
}

int run_info(const std::string& path) {
  HumanoidAsset asset;
  try {
    // The one input-format table (scene/input_formats.h) decides what the path is, as it does for every command.
    const InputFormatId format = identify_input(path).id;
    if (format != InputFormatId::HAnim) return run_other_info(path, format);
    asset = load_humanoid_file(path);
  } catch (const std::exception& e) {
    print_error("info", error_text(e));
    return 1;
  }
  const Skeleton& s = asset.skeleton;
  std::set<std::uint32_t> weighted;
  for (const SkinInfluence& inf : s.skin_influences) weighted.insert(inf.vertex);
  std::size_t weighted_joints = 0;
  for (std::size_t j = 0; j + 1 < s.skin_offsets.size(); ++j) weighted_joints += s.skin_offsets[j + 1] > s.skin_offsets[j];
  std::size_t limited = 0;
  for (const JointLimits& l : s.limits) limited += l.present;
  const RestStature stature = rest_stature(s);
  int max_depth = 0;
  for (std::size_t j = 0; j < s.joint_count(); ++j) max_depth = std::max(max_depth, s.depth(static_cast<int>(j)));

  std::cout << "file:       " << path << "\n"
            << "format:     " << (asset.format == HumanoidFormat::X3D ? "X3D H-Anim" : "paper-era humanoid XML") << "\n"
            << "humanoid:   " << (s.name.empty() ? "(unnamed)" : s.name) << "\n"
            << "naming:     " << to_string(s.naming) << "\n"
            << "joints:     " << s.joint_count() << " (root " << (s.joint_count() ? s.joint_names[0] : "-")
            << ", depth " << max_depth << ", " << limited << " with limits)\n"
            << "segments:   " << s.segments.size() << "\n"
            << "sites:      " << s.sites.size() << "\n"
            << "stature_m:  " << stature.metres << " (" << stature.source << ")\n"
            << "skin:       " << s.skin_points.size() << " vertices, " << s.skin_triangles.size() / 3 << " triangles, "
            << weighted.size() << " weighted by " << weighted_joints << " joints\n"
            << "clips:      " << asset.clips.size() << "\n";
  for (const AnimationClip& c : asset.clips)
    std::cout << "  " << c.name << ": " << c.duration << " s, " << c.rotations.size() << " rotation + "
              << c.translations.size() << " translation channels" << (c.loop ? ", loops" : "") << "\n";
  for (const std::string& w : s.warnings) std::cout << "warning:    " << w << "\n";
  return 0;
}

}  // namespace

void add_info_command(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("info", "Load any supported input (X3D H-Anim, paper-era XML, BVH, OBJ, glTF, a "
                                         "MakeHuman folder) and print a summary");
  auto path = std::make_shared<std::string>();
  cmd->add_option("FILE", *path, "Input file")->required();
  add_input_limit_option(*cmd);
  cmd->callback([path, &exit_code] { exit_code = run_info(*path); });
}

}  // namespace strata::cli
