#include "io/makehuman.h"

#include <algorithm>
#include <cmath>
#include <array>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/mesh_check.h"
#include "io/hanim_loader.h"

namespace strata {
namespace {

// Splits "upperarm02.L" into ("upperarm02", "l"); sideless bones get an empty side.
std::pair<std::string_view, std::string_view> split_side(std::string_view bone) {
  if (bone.size() > 2 && bone[bone.size() - 2] == '.') {
    const char s = bone.back();
    if (s == 'L') return {bone.substr(0, bone.size() - 2), "l"};
    if (s == 'R') return {bone.substr(0, bone.size() - 2), "r"};
  }
  return {bone, ""};
}

bool starts_with_any(std::string_view s, std::initializer_list<std::string_view> prefixes) {
  for (std::string_view p : prefixes)
    if (s.starts_with(p)) return true;
  return false;
}

// Facial, eye and tongue bones: the head part, moved by skullbase.
bool is_face_bone(std::string_view base) {
  return base == "head" || base == "jaw" || base == "eye" ||
         starts_with_any(base, {"levator", "oculi", "orbicularis", "oris", "risorius", "special", "temporalis",
                                "tongue"});
}

// Returns the table's own copy of `name` (so the caller can hand out a view), or an empty view.
std::string_view interned(const std::vector<std::string>& table, const std::string& name) {
  for (const std::string& s : table)
    if (s == name) return s;
  return {};
}

const std::vector<std::string>& hanim25_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = {"HumanoidRoot", "sacroiliac", "vl5", "vt6", "vt1", "vc4", "skullbase"};
    for (const char* side : {"l_", "r_"})
      for (const char* j : {"hip", "knee", "ankle", "midtarsal", "sternoclavicular", "acromioclavicular", "shoulder",
                            "elbow", "wrist"})
        n.push_back(std::string(side) + j);
    return n;
  }();
  return names;
}

// The H-Anim centre of each joint is one MakeHuman joint, chosen by where it sits on the body: the MH spine has
// six bones from the pelvis to the head, so vl5 (lumbar), vt6 (mid-thoracic, ~3/4 of the way from vl5 to vt1),
// vt1 (base of the neck) and vc4 (mid-neck) take the nearest MH bone heads. The midtarsal joint is the foot
// bone's tail (mid-foot, ahead of the ankle), the acromioclavicular the clavicle's tail.
const std::vector<std::pair<std::string, std::string>>& joint_sources() {
  static const std::vector<std::pair<std::string, std::string>> table = [] {
    std::vector<std::pair<std::string, std::string>> t = {
        {"HumanoidRoot", ""},  // midpoint of the hips, below sacroiliac as in H-Anim's default
        {"sacroiliac", "spine05____head"}, {"vl5", "spine04____head"}, {"vt6", "spine01____head"},
        {"vt1", "neck01____head"},         {"vc4", "neck02____head"},  {"skullbase", "head____head"}};
    for (const auto& [side, mh] : {std::pair{"l_", ".L"}, std::pair{"r_", ".R"}}) {
      const std::string s(side), m(mh);
      t.push_back({s + "hip", "upperleg01" + m + "____head"});
      t.push_back({s + "knee", "lowerleg01" + m + "____head"});
      t.push_back({s + "ankle", "foot" + m + "____head"});
      t.push_back({s + "midtarsal", "foot" + m + "____tail"});
      t.push_back({s + "sternoclavicular", "clavicle" + m + "____head"});
      t.push_back({s + "acromioclavicular", "clavicle" + m + "____tail"});
      t.push_back({s + "shoulder", "upperarm01" + m + "____head"});
      t.push_back({s + "elbow", "lowerarm01" + m + "____head"});
      t.push_back({s + "wrist", "wrist" + m + "____head"});
    }
    return t;
  }();
  return table;
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& message) {
  throw LoadError(file.string() + ": " + message);
}

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, "cannot open file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

nlohmann::json parse_json(std::string_view text, const std::filesystem::path& file) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    fail(file, std::string("invalid JSON: ") + e.what());
  }
}

// A JSON value for an error message: short, and without serialising a (hostile, deeply nested) value whole, which
// recurses once per nesting level.
std::string describe(const nlohmann::json& value) {
  if (value.is_primitive()) {
    std::string text = value.dump();
    if (text.size() > 40) text = text.substr(0, 37) + "...";
    return text;
  }
  return std::string("a JSON ") + value.type_name();
}

// Bone names parents-first (the file lists them alphabetically); throws on a missing parent or a cycle.
std::vector<std::string> sort_bones(const nlohmann::json& bones, const std::filesystem::path& file) {
  std::unordered_map<std::string, std::string> parent;
  for (const auto& [name, bone] : bones.items()) {
    if (!bone.is_object()) fail(file, "bone '" + name + "': expected an object");
    const auto p = bone.find("parent");
    if (p != bone.end() && !p->is_null() && !p->is_string())
      fail(file, "bone '" + name + "': 'parent' must be a bone name or null");
    parent[name] = (p == bone.end() || p->is_null()) ? std::string() : p->get<std::string>();
  }
  std::unordered_map<std::string, int> state;  // 0 unseen, 1 on the current path, 2 placed
  std::vector<std::string> order;
  // Walks up from `name` to the first placed (or root) ancestor, then places that path top-down. Iterative: a
  // recursive walk overflows the stack on a long (hostile) parent chain.
  std::vector<std::string> path;
  auto place = [&](const std::string& start) {
    path.clear();
    for (std::string name = start;;) {
      int& s = state[name];
      if (s == 2) break;
      if (s == 1) fail(file, "bone '" + name + "': parent chain has a cycle");
      s = 1;
      path.push_back(name);
      const std::string& p = parent.at(name);
      if (p.empty()) break;
      if (!parent.count(p)) fail(file, "bone '" + name + "': parent '" + p + "' is not a bone");
      name = p;
    }
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      state[*it] = 2;
      order.push_back(*it);
    }
  };
  for (const auto& [name, unused] : parent) place(name);
  return order;
}

}  // namespace

std::string_view makehuman_bone_part(std::string_view bone) {
  const auto [base, side] = split_side(bone);
  const std::vector<std::string>& parts = paper_part_names();
  if (side.empty()) {
    if (base == "root" || base == "spine05") return interned(parts, "hip");
    if (base == "spine04" || base == "spine03" || base == "spine02") return interned(parts, "abdomen");
    if (base == "spine01") return interned(parts, "chest");
    if (base.starts_with("neck")) return interned(parts, "neck");
    if (is_face_bone(base)) return interned(parts, "head");
    return {};
  }
  const std::string s(side);
  if (base == "eye") return interned(parts, s + "Eye");
  if (is_face_bone(base)) return interned(parts, "head");
  if (base == "breast") return interned(parts, "chest");
  if (base == "pelvis") return interned(parts, "hip");
  if (base == "clavicle") return interned(parts, s + "Collar");
  if (base == "shoulder01" || base.starts_with("upperarm")) return interned(parts, s + "Shldr");
  if (base.starts_with("lowerarm")) return interned(parts, s + "ForeArm");
  if (base == "wrist" || base.starts_with("metacarpal")) return interned(parts, s + "Hand");
  if (base.starts_with("upperleg")) return interned(parts, s + "Thigh");
  if (base.starts_with("lowerleg")) return interned(parts, s + "Shin");
  if (base == "foot") return interned(parts, s + "Foot");
  if (base.starts_with("toe")) return interned(parts, s + "Toe");
  // finger<N>-<k>: N = 1 thumb .. 5 pinky, k = 1..3 from the palm out.
  if (base.size() == 9 && base.starts_with("finger") && base[7] == '-') {
    static constexpr std::array<const char*, 5> fingers = {"Thumb", "Index", "Mid", "Ring", "Pinky"};
    const int n = base[6] - '1', k = base[8] - '0';
    if (n >= 0 && n < 5 && k >= 1 && k <= 3) return interned(parts, s + fingers[n] + std::to_string(k));
  }
  return {};
}

std::string_view makehuman_bone_joint(std::string_view bone) {
  const auto [base, side] = split_side(bone);
  const std::vector<std::string>& joints = hanim25_names();
  if (is_face_bone(base)) return interned(joints, "skullbase");
  if (side.empty()) {
    // spine05 spans sacroiliac..vl5, a stretch no 25-joint H-Anim joint but the root moves.
    if (base == "root" || base == "spine05") return interned(joints, "HumanoidRoot");
    if (base == "spine04" || base == "spine03" || base == "spine02") return interned(joints, "vl5");
    if (base == "spine01") return interned(joints, "vt6");
    if (base == "neck01") return interned(joints, "vt1");
    if (base == "neck02" || base == "neck03") return interned(joints, "vc4");
    return {};
  }
  const std::string s = std::string(side) + "_";
  if (base == "breast") return interned(joints, "vt6");
  if (base == "pelvis") return interned(joints, "sacroiliac");
  if (base == "clavicle") return interned(joints, s + "sternoclavicular");
  if (base == "shoulder01") return interned(joints, s + "acromioclavicular");
  if (base.starts_with("upperarm")) return interned(joints, s + "shoulder");
  if (base.starts_with("lowerarm")) return interned(joints, s + "elbow");
  if (base == "wrist" || base.starts_with("metacarpal") || base.starts_with("finger"))
    return interned(joints, s + "wrist");
  if (base.starts_with("upperleg")) return interned(joints, s + "hip");
  if (base.starts_with("lowerleg")) return interned(joints, s + "knee");
  if (base == "foot") return interned(joints, s + "ankle");
  if (base.starts_with("toe")) return interned(joints, s + "midtarsal");
  return {};
}

std::string_view makehuman_joint_source(std::string_view hanim_joint) {
  for (const auto& [joint, source] : joint_sources())
    if (joint == hanim_joint) return source;
  return {};
}

ImportedBody load_makehuman(const std::filesystem::path& dir) {
  const std::string obj = read_file(dir / "base.obj");
  const std::string skel = read_file(dir / "default.mhskel");
  const std::string weights = read_file(dir / "default_weights.mhw");
  return load_makehuman_text(obj, skel, weights, dir.string());
}

ImportedBody load_makehuman_text(std::string_view base_obj, std::string_view mhskel, std::string_view mhw,
                                 std::string_view dir_name) {
  const std::filesystem::path dir{std::string(dir_name)};
  const std::filesystem::path obj_path = dir / "base.obj", skel_path = dir / "default.mhskel",
                              weights_path = dir / "default_weights.mhw";
  ImportedBody body;

  // --- the skin: group "body", decimetres -> metres --------------------------------------------------------
  ObjSource src;
  Mesh obj = load_obj_text(base_obj, obj_path.string(), ObjOptions{{"body"}, 0.1f}, &src);
  const std::size_t n = obj.vertex_count();
  std::vector<std::int32_t> mesh_vertex(src.file_positions.size(), -1);
  for (std::size_t v = 0; v < n; ++v) mesh_vertex[src.file_vertex[v]] = static_cast<std::int32_t>(v);

  // --- the MakeHuman skeleton: joint positions = mean of their marker vertices ---------------------------------
  const nlohmann::json skel = parse_json(mhskel, skel_path);
  if (!skel.contains("bones") || !skel["bones"].is_object() || !skel.contains("joints") ||
      !skel["joints"].is_object())
    fail(skel_path, "expected objects 'bones' and 'joints'");
  const std::vector<std::string> bone_order = sort_bones(skel["bones"], skel_path);
  auto joint_position = [&](const std::string& key) {
    const auto it = skel["joints"].find(key);
    if (it == skel["joints"].end() || !it->is_array() || it->empty())
      fail(skel_path, "joint '" + key + "': missing or has no vertices");
    glm::dvec3 sum(0.0);
    for (const auto& index : *it) {
      if (!index.is_number_integer() || index.get<long>() < 0 ||
          index.get<std::size_t>() >= src.file_positions.size())
        fail(skel_path, "joint '" + key + "': vertex index " + describe(index) + " out of range (" +
                            std::to_string(src.file_positions.size()) + " vertices in base.obj)");
      sum += glm::dvec3(src.file_positions[index.get<std::size_t>()]);
    }
    return glm::vec3(sum / static_cast<double>(it->size()));
  };

  // --- weights: per body vertex, normalised, then strongest bone -> part, fold onto H-Anim joints ------------
  const nlohmann::json weights_file = parse_json(mhw, weights_path);
  if (!weights_file.contains("weights") || !weights_file["weights"].is_object())
    fail(weights_path, "expected an object 'weights'");
  const std::vector<std::string>& joint_names = hanim25_names();
  std::vector<std::vector<std::pair<std::uint32_t, float>>> influences(n);  // (bone id, weight)
  std::vector<std::string> bones;
  for (const auto& [bone, list] : weights_file["weights"].items()) {
    const std::uint32_t id = static_cast<std::uint32_t>(bones.size());
    bool weighs_body = false;
    if (!list.is_array()) fail(weights_path, "bone '" + bone + "': weights are not a list");
    for (const auto& pair : list) {
      if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number_integer() || !pair[1].is_number())
        fail(weights_path, "bone '" + bone + "': expected [vertex, weight] pairs, got " + describe(pair));
      const long v = pair[0].get<long>();
      const float w = pair[1].get<float>();
      if (v < 0 || static_cast<std::size_t>(v) >= mesh_vertex.size())
        fail(weights_path, "bone '" + bone + "': vertex " + std::to_string(v) + " out of range");
      if (!std::isfinite(w) || w < 0.0f)
        fail(weights_path, "bone '" + bone + "': vertex " + std::to_string(v) + " has weight " + describe(pair[1]));
      if (mesh_vertex[v] < 0 || w == 0.0f) continue;
      influences[mesh_vertex[v]].emplace_back(id, w);
      weighs_body = true;
    }
    if (weighs_body && (makehuman_bone_part(bone).empty() || makehuman_bone_joint(bone).empty()))
      fail(weights_path, "bone '" + bone + "' weighs the body but has no part or H-Anim joint mapping");
    bones.push_back(bone);
  }
  std::vector<std::uint16_t> bone_part(bones.size(), 0);
  std::vector<std::int16_t> bone_joint(bones.size(), 0);
  const std::vector<std::string>& parts = paper_part_names();
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const std::string_view part = makehuman_bone_part(bones[b]), joint = makehuman_bone_joint(bones[b]);
    if (part.empty()) continue;  // weighs only helper geometry
    bone_part[b] = static_cast<std::uint16_t>(std::find(parts.begin(), parts.end(), part) - parts.begin());
    bone_joint[b] = static_cast<std::int16_t>(std::find(joint_names.begin(), joint_names.end(), joint) -
                                              joint_names.begin());
  }

  body.skin.joints.resize(n);
  body.skin.weights.resize(n);
  obj.part.assign(n, 0);
  std::vector<float> folded(joint_names.size());
  std::vector<std::int16_t> order(joint_names.size());
  for (std::size_t v = 0; v < n; ++v) {
    const auto& inf = influences[v];
    float sum = 0.0f;
    for (const auto& [b, w] : inf) sum += w;
    if (sum <= 0.0f)
      fail(weights_path, "body vertex " + std::to_string(src.file_vertex[v]) + " has no weights");
    if (!std::isfinite(sum))
      fail(weights_path, "body vertex " + std::to_string(src.file_vertex[v]) + ": its weights overflow a float");
    const auto strongest = std::max_element(inf.begin(), inf.end(),
                                            [](const auto& a, const auto& b) { return a.second < b.second; });
    obj.part[v] = bone_part[strongest->first];
    // The eye bones weigh the lids ~5 %, never most, so by the strongest bone no vertex would be an eye's; every
    // vertex they touch is taken as that eye's part (141 a side), so the body has all 53 of the paper's parts.
    for (const auto& [b, w] : inf)
      if (const std::string& part = parts[bone_part[b]]; part == "lEye" || part == "rEye") obj.part[v] = bone_part[b];
    std::fill(folded.begin(), folded.end(), 0.0f);
    for (const auto& [b, w] : inf) folded[bone_joint[b]] += w / sum;
    for (std::size_t j = 0; j < order.size(); ++j) order[j] = static_cast<std::int16_t>(j);
    std::stable_sort(order.begin(), order.end(), [&](std::int16_t a, std::int16_t b) { return folded[a] > folded[b]; });
    float kept = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k) kept += folded[order[k]];
    for (int k = 0; k < kMaxInfluences; ++k) {
      const bool used = folded[order[k]] > 0.0f;
      body.skin.joints[v][k] = used ? order[k] : std::int16_t{0};
      body.skin.weights[v][k] = used ? folded[order[k]] / kept : 0.0f;
    }
  }
  obj.part_names = parts;

  // --- the H-Anim skeleton: the shipped 25-joint topology with MakeHuman centres, soles at y = 0 ------------
  float floor_y = std::numeric_limits<float>::max();
  for (const glm::vec3& p : obj.positions) floor_y = std::min(floor_y, p.y);
  const glm::vec3 shift(0.0f, -floor_y, 0.0f);
  for (glm::vec3& p : obj.positions) p += shift;

  Skeleton skeleton = load_default_humanoid().skeleton;
  std::vector<glm::vec3> centers(skeleton.joint_count());
  for (std::size_t j = 0; j < skeleton.joint_count(); ++j) {
    const std::string_view source = makehuman_joint_source(skeleton.joint_names[j]);
    if (skeleton.joint_names[j] == "HumanoidRoot")
      centers[j] = 0.5f * (joint_position("upperleg01.L____head") + joint_position("upperleg01.R____head"));
    else if (source.empty())
      fail(skel_path, "no MakeHuman joint for H-Anim joint '" + skeleton.joint_names[j] + "'");
    else
      centers[j] = joint_position(std::string(source));
    centers[j] += shift;
  }
  // The skin's joint indices follow hanim25_names(); re-index them to the skeleton's order.
  std::vector<std::int16_t> to_skeleton(joint_names.size());
  for (std::size_t j = 0; j < joint_names.size(); ++j) {
    const std::int32_t s = skeleton.find_joint(joint_names[j]);
    if (s < 0) fail(skel_path, "the default skeleton lacks joint '" + joint_names[j] + "'");
    to_skeleton[j] = static_cast<std::int16_t>(s);
  }
  for (std::size_t v = 0; v < n; ++v)
    for (int k = 0; k < kMaxInfluences; ++k)
      if (body.skin.weights[v][k] > 0.0f) body.skin.joints[v][k] = to_skeleton[body.skin.joints[v][k]];
  // Segments' centres of mass and sites move with their joint, so they keep their place relative to it.
  for (SkeletonSegment& s : skeleton.segments)
    if (s.joint >= 0) s.center_of_mass += centers[s.joint] - skeleton.centers[s.joint];
  for (SkeletonSite& s : skeleton.sites)
    if (s.joint >= 0) s.position += centers[s.joint] - skeleton.centers[s.joint];
  skeleton.centers = std::move(centers);
  skeleton.name = "MakeHuman_hm08";
  skeleton.source = dir.string();
  skeleton.skin_points.clear();
  skeleton.skin_triangles.clear();
  skeleton.skin_offsets.clear();
  skeleton.skin_influences.clear();
  skeleton.warnings.clear();

  obj.name = "MakeHuman_hm08/body";
  validate_mesh(obj, obj_path.string());
  body.skeleton = std::move(skeleton);
  body.mesh = std::move(obj);
  body.warnings.push_back(skel_path.string() + ": " + std::to_string(bone_order.size()) +
                          " bones; rest pose kept as the file's A-pose");
  return body;
}

}  // namespace strata
