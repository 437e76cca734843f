#include "rig/binding.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "data/embedded.h"
#include "io/load_error.h"
#include "rig/harmonic_weights.h"

namespace strata {
namespace {

using Json = nlohmann::json;

// ---- Joint vocabulary ----------------------------------------------------------------------------------------

// The H-Anim 1.1 joint set. Table joints are checked against it (and against the 2019 names the skeleton module
// knows) when a table is loaded, so a typo fails there rather than at bind time against some skeleton.
const std::unordered_set<std::string>& hanim_joint_names() {
  static const std::unordered_set<std::string> names = [] {
    std::unordered_set<std::string> n = {"HumanoidRoot", "sacroiliac", "skullbase", "temporomandibular"};
    for (int k = 1; k <= 5; ++k) n.insert("vl" + std::to_string(k));
    for (int k = 1; k <= 12; ++k) n.insert("vt" + std::to_string(k));
    for (int k = 1; k <= 7; ++k) n.insert("vc" + std::to_string(k));
    for (std::string s : {"l_", "r_"}) {
      for (const char* j : {"hip", "knee", "ankle", "subtalar", "midtarsal", "metatarsal", "sternoclavicular",
                            "acromioclavicular", "shoulder", "elbow", "wrist", "eyelid_joint", "eyeball_joint",
                            "eyebrow_joint", "thumb1", "thumb2", "thumb3"})
        n.insert(s + j);
      for (const char* finger : {"index", "middle", "ring", "pinky"})
        for (int k = 0; k <= 3; ++k) n.insert(s + finger + std::to_string(k));
    }
    return n;
  }();
  return names;
}

bool known_joint_name(const std::string& name) {
  const auto& names = hanim_joint_names();
  return names.count(name) > 0 || names.count(std::string(canonical_joint_name(name))) > 0 || is_hanim2019_name(name);
}

bool known_part_name(const std::string& name) {
  const auto& parts = paper_part_names();
  return std::find(parts.begin(), parts.end(), name) != parts.end();
}

// ---- JSON helpers --------------------------------------------------------------------------------------------

Json parse_json(std::string_view text, const std::string& source) {
  try {
    return Json::parse(text.begin(), text.end());
  } catch (const Json::exception& e) {
    // Not only parse_error: a number too large for a double ("1e400") is an out_of_range (found by fuzzing).
    throw LoadError(source + ": invalid JSON: " + e.what());
  }
}

glm::vec3 read_vec3(const Json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) throw LoadError(where + ": expected an array of 3 numbers");
  glm::vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) throw LoadError(where + ": expected an array of 3 numbers");
    v[i] = j[i].get<float>();
    if (!std::isfinite(v[i])) throw LoadError(where + ": non-finite coordinate");
  }
  return v;
}

float read_number(const Json& obj, const char* key, const std::string& where) {
  if (!obj.contains(key) || !obj[key].is_number()) throw LoadError(where + ": '" + key + "' must be a number");
  const float x = obj[key].get<float>();
  if (!std::isfinite(x)) throw LoadError(where + ": '" + key + "' is not finite");
  return x;
}

std::vector<std::string> read_names(const Json& obj, const char* key, const std::string& where,
                                    bool (*known)(const std::string&), const char* what) {
  std::vector<std::string> out;
  if (!obj.contains(key)) return out;
  const Json& list = obj[key];
  if (!list.is_array()) throw LoadError(where + ": '" + key + "' must be an array of names");
  for (const Json& item : list) {
    if (!item.is_string()) throw LoadError(where + ": '" + key + "' must be an array of names");
    std::string name = item.get<std::string>();
    if (!known(name)) throw LoadError(where + ": unknown " + what + " '" + name + "'");
    out.push_back(std::move(name));
  }
  return out;
}

void check_keys(const Json& obj, std::initializer_list<const char*> allowed, const std::string& where) {
  for (const auto& [key, value] : obj.items()) {
    if (key.starts_with("_")) continue;  // "_doc" and friends: comments, which JSON lacks
    bool ok = false;
    for (const char* a : allowed) ok |= key == a;
    if (!ok) throw LoadError(where + ": unknown key '" + key + "'");
  }
}

SkinSelection parse_selection(const Json& e, const std::string& source, std::size_t index) {
  std::string where = source + ": overrides[" + std::to_string(index) + "]";
  if (!e.is_object()) throw LoadError(where + ": expected an object");
  SkinSelection s;
  if (e.contains("name")) {
    if (!e["name"].is_string()) throw LoadError(where + ": 'name' must be a string");
    s.name = e["name"].get<std::string>();
    where += " '" + s.name + "'";
  } else {
    s.name = "overrides[" + std::to_string(index) + "]";
  }
  check_keys(e, {"name", "vertices", "mesh_vertices", "sphere", "box", "parts", "joints", "blend", "falloff_m"},
             where);
  const int kinds = int(e.contains("vertices")) + int(e.contains("sphere")) + int(e.contains("box"));
  if (kinds != 1) throw LoadError(where + ": needs exactly one of 'vertices', 'sphere', 'box'");
  if (e.contains("vertices")) {
    s.kind = SkinSelection::Kind::Vertices;
    const Json& ids = e["vertices"];
    if (!ids.is_array()) throw LoadError(where + ": 'vertices' must be an array of vertex ids");
    for (const Json& id : ids) {
      if (!id.is_number_integer() || id.get<std::int64_t>() < 0 ||
          id.get<std::int64_t>() > std::numeric_limits<std::uint32_t>::max())
        throw LoadError(where + ": 'vertices' must hold non-negative integer ids");
      s.vertices.push_back(static_cast<std::uint32_t>(id.get<std::int64_t>()));
    }
    if (e.contains("mesh_vertices")) {
      const Json& n = e["mesh_vertices"];
      if (!n.is_number_integer() || n.get<std::int64_t>() < 0 ||
          n.get<std::int64_t>() > std::numeric_limits<std::uint32_t>::max())
        throw LoadError(where + ": 'mesh_vertices' must be a non-negative integer (a vertex count)");
      s.mesh_vertices = static_cast<std::uint32_t>(n.get<std::int64_t>());
    }
  } else if (e.contains("mesh_vertices")) {
    throw LoadError(where + ": 'mesh_vertices' is only valid with 'vertices'");
  } else if (e.contains("sphere")) {
    s.kind = SkinSelection::Kind::Sphere;
    const Json& sp = e["sphere"];
    if (!sp.is_object() || !sp.contains("center")) throw LoadError(where + ": 'sphere' needs 'center' and 'radius'");
    s.center = read_vec3(sp["center"], where + ": sphere.center");
    s.radius = read_number(sp, "radius", where + ": sphere");
    if (s.radius <= 0.0f) throw LoadError(where + ": sphere radius must be positive");
  } else {
    s.kind = SkinSelection::Kind::Box;
    const Json& b = e["box"];
    if (!b.is_object() || !b.contains("min") || !b.contains("max"))
      throw LoadError(where + ": 'box' needs 'min' and 'max'");
    s.box_min = read_vec3(b["min"], where + ": box.min");
    s.box_max = read_vec3(b["max"], where + ": box.max");
    for (int i = 0; i < 3; ++i)
      if (s.box_min[i] > s.box_max[i]) throw LoadError(where + ": box min exceeds max");
  }
  s.parts = read_names(e, "parts", where, known_part_name, "part");
  s.joints = read_names(e, "joints", where, known_joint_name, "joint");
  if (e.contains("blend")) {
    const std::string blend = e["blend"].is_string() ? e["blend"].get<std::string>() : std::string();
    if (blend == "parent")
      s.blend = SkinSelection::Blend::Parent;
    else if (blend == "nearest_two")
      s.blend = SkinSelection::Blend::NearestTwo;
    else if (blend == "harmonic")
      s.blend = SkinSelection::Blend::Harmonic;
    else
      throw LoadError(where + ": 'blend' must be \"parent\", \"nearest_two\" or \"harmonic\"");
  }
  if (e.contains("falloff_m")) {
    s.falloff_m = read_number(e, "falloff_m", where);
    if (s.falloff_m < 0.0f) throw LoadError(where + ": 'falloff_m' must not be negative");
  }
  if (s.blend == SkinSelection::Blend::Harmonic && (!s.joints.empty() || s.falloff_m > 0.0f))
    throw LoadError(where +
                    ": a harmonic blend takes its joints from around the selection: no 'joints' or 'falloff_m'");
  return s;
}

// ---- Building bindings ---------------------------------------------------------------------------------------

struct Influence {
  int joint;
  double weight;
};

// Sets vertex v's influences: merges repeated joints, keeps the kMaxInfluences heaviest (ties: lower joint
// index, for determinism) and renormalises to a sum of 1.
void set_influences(SkinBinding& binding, std::size_t v, std::vector<Influence> in) {
  std::sort(in.begin(), in.end(), [](const Influence& a, const Influence& b) { return a.joint < b.joint; });
  std::vector<Influence> merged;
  for (const Influence& i : in) {
    if (!(i.weight > 0.0)) continue;
    if (!merged.empty() && merged.back().joint == i.joint)
      merged.back().weight += i.weight;
    else
      merged.push_back(i);
  }
  std::stable_sort(merged.begin(), merged.end(),
                   [](const Influence& a, const Influence& b) { return a.weight > b.weight; });
  if (merged.size() > static_cast<std::size_t>(kMaxInfluences)) merged.resize(kMaxInfluences);
  double total = 0.0;
  for (const Influence& i : merged) total += i.weight;
  binding.joints[v].fill(0);
  binding.weights[v].fill(0.0f);
  for (std::size_t k = 0; k < merged.size(); ++k) {
    binding.joints[v][k] = static_cast<std::int16_t>(merged[k].joint);
    binding.weights[v][k] = static_cast<float>(merged[k].weight / total);
  }
}

std::vector<Influence> influences_of(const SkinBinding& binding, std::size_t v) {
  std::vector<Influence> out;
  for (int k = 0; k < kMaxInfluences; ++k)
    if (binding.weights[v][k] > 0.0f) out.push_back({binding.joints[v][k], binding.weights[v][k]});
  return out;
}

double distance(const glm::vec3& a, const glm::vec3& b) { return glm::length(glm::dvec3(a) - glm::dvec3(b)); }

// Weight of joint a against joint b, inversely proportional to the distances: w_a = (1/d_a) / (1/d_a + 1/d_b).
double inverse_distance_weight(double da, double db) {
  if (da + db <= 0.0) return 0.5;
  return db / (da + db);
}

double smoothstep01(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// How strongly selection s claims point p: 1 inside, fading to 0 over the last falloff_m metres to the edge.
double selection_strength(const SkinSelection& s, const glm::vec3& p) {
  double inside = 0.0;  // distance from p to the selection's boundary, negative outside
  if (s.kind == SkinSelection::Kind::Sphere) {
    inside = s.radius - distance(p, s.center);
  } else {
    inside = std::numeric_limits<double>::max();
    for (int i = 0; i < 3; ++i)
      inside = std::min({inside, double(p[i]) - s.box_min[i], double(s.box_max[i]) - p[i]});
  }
  if (inside < 0.0) return 0.0;
  if (s.falloff_m <= 0.0f) return 1.0;
  return smoothstep01(inside / s.falloff_m);
}

}  // namespace

void apply_selection(const SkinSelection& s, const Mesh& mesh, const Skeleton& skeleton, SkinBinding& binding) {
  if (s.kind == SkinSelection::Kind::Vertices && s.mesh_vertices != 0 && s.mesh_vertices != mesh.vertex_count())
    return;  // ids of another mesh (level) of the body
  std::vector<int> candidates;
  if (s.joints.empty()) {
    for (std::size_t j = 0; j < skeleton.joint_count(); ++j) candidates.push_back(static_cast<int>(j));
  } else {
    for (const std::string& name : s.joints)
      if (int j = skeleton.find_joint(name); j >= 0) candidates.push_back(j);
  }
  if (candidates.empty()) return;

  std::vector<bool> part_ok(mesh.part_names.size(), s.parts.empty());
  for (std::size_t p = 0; p < mesh.part_names.size(); ++p)
    for (const std::string& name : s.parts) part_ok[p] = part_ok[p] || mesh.part_names[p] == name;

  // Harmonic: the selection is the free region of harmonic_weights; its surroundings give the values.
  if (s.blend == SkinSelection::Blend::Harmonic) {
    std::vector<std::uint8_t> free(mesh.vertex_count(), 0);
    auto in_parts = [&](std::size_t v) { return mesh.part.empty() || part_ok[mesh.part[v]]; };
    if (s.kind == SkinSelection::Kind::Vertices) {
      for (std::uint32_t v : s.vertices) {
        if (v >= mesh.vertex_count())
          throw std::invalid_argument("binding override '" + s.name + "': vertex " + std::to_string(v) +
                                      " but the mesh has " + std::to_string(mesh.vertex_count()));
        free[v] = in_parts(v);
      }
    } else {
      for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
        free[v] = in_parts(v) && selection_strength(s, mesh.positions[v]) > 0.0;
    }
    const std::vector<std::vector<JointWeight>> weights = harmonic_weights(mesh, binding, free);
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      if (weights[v].empty()) continue;
      std::vector<Influence> in;
      for (const JointWeight& w : weights[v]) in.push_back({w.joint, w.weight});
      set_influences(binding, v, std::move(in));
    }
    return;
  }

  auto rebind = [&](std::size_t v, double strength) {
    if (strength <= 0.0) return;
    if (!mesh.part.empty() && !part_ok[mesh.part[v]]) return;
    const glm::vec3& p = mesh.positions[v];
    // Closest and second-closest candidates (ties: the earlier one, so the result does not depend on hashing).
    int best = -1, second = -1;
    double d_best = std::numeric_limits<double>::max(), d_second = d_best;
    for (int j : candidates) {
      const double d = distance(p, skeleton.centers[j]);
      if (d < d_best) {
        second = best, d_second = d_best;
        best = j, d_best = d;
      } else if (d < d_second) {
        second = j, d_second = d;
      }
    }
    int other = -1;
    double d_other = 0.0;
    if (s.blend == SkinSelection::Blend::NearestTwo && second >= 0) {
      other = second, d_other = d_second;
    } else if (skeleton.parents[best] >= 0) {
      other = skeleton.parents[best];
      d_other = distance(p, skeleton.centers[other]);
    }
    std::vector<Influence> in;
    if (other < 0) {
      in.push_back({best, strength});
    } else {
      const double w = inverse_distance_weight(d_best, d_other);
      in.push_back({best, strength * w});
      in.push_back({other, strength * (1.0 - w)});
    }
    if (strength < 1.0)
      for (Influence i : influences_of(binding, v)) in.push_back({i.joint, i.weight * (1.0 - strength)});
    set_influences(binding, v, std::move(in));
  };

  if (s.kind == SkinSelection::Kind::Vertices) {
    for (std::uint32_t v : s.vertices) {
      if (v >= mesh.vertex_count())
        throw std::invalid_argument("binding override '" + s.name + "': vertex " + std::to_string(v) +
                                    " but the mesh has " + std::to_string(mesh.vertex_count()));
      rebind(v, 1.0);
    }
  } else {
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) rebind(v, selection_strength(s, mesh.positions[v]));
  }
}

namespace {

// Step 2 for one joint and its parent: vertices bound to either alone and within radius of the joint blend the
// two.
void blend_near_joint(const BlendJoint& bj, const Mesh& mesh, const Skeleton& skeleton, Step2Weights mode,
                      SkinBinding& binding) {
  const int joint = skeleton.find_joint(bj.joint);
  if (joint < 0 || skeleton.parents[joint] < 0 || bj.radius_m <= 0.0f) return;
  const int parent = skeleton.parents[joint];
  const glm::dvec3 cj(skeleton.centers[joint]), cp(skeleton.centers[parent]);
  // Crease axis: the bisector of the parent bone and the child bone when joint has one child, so a limb bent at rest
  // (a knee) gets its blend plane across the bend rather than across the upper bone only.
  glm::dvec3 axis = cj - cp;
  axis = glm::length(axis) > 0.0 ? glm::normalize(axis) : glm::dvec3(0.0, -1.0, 0.0);
  int child = -1, children = 0;
  for (std::size_t k = 0; k < skeleton.joint_count(); ++k)
    if (skeleton.parents[k] == joint) child = static_cast<int>(k), ++children;
  if (children == 1) {
    const glm::dvec3 down = glm::dvec3(skeleton.centers[child]) - cj;
    if (glm::length(down) > 0.0) {
      const glm::dvec3 bis = axis + glm::normalize(down);
      if (glm::length(bis) > 1e-6) axis = glm::normalize(bis);
    }
  }
  const double r = bj.radius_m;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    if (binding.influence_count(v) != 1) continue;
    const int bound = binding.joints[v][0];
    if (bound != joint && bound != parent) continue;
    const glm::dvec3 p(mesh.positions[v]);
    const double dj = glm::length(p - cj);
    if (dj >= r) continue;
    double wj = 0.0;
    if (mode == Step2Weights::InverseDistance) {
      wj = inverse_distance_weight(dj, glm::length(p - cp));
    } else {
      const double x = glm::dot(p - cj, axis);
      const double half = std::sqrt(std::max(r * r - (dj * dj - x * x), 0.0));
      wj = half > 0.0 ? smoothstep01((x + half) / (2.0 * half)) : (x >= 0.0 ? 1.0 : 0.0);
    }
    set_influences(binding, v, {{joint, wj}, {parent, 1.0 - wj}});
  }
}

}  // namespace

const std::string* BindingTables::joint_of_part(std::string_view part) const {
  for (const auto& [p, j] : part_joints)
    if (p == part) return &j;
  return nullptr;
}

BindingTables load_binding_tables(std::string_view part_joints_json, std::string_view overrides_json,
                                  std::string_view part_joints_source, std::string_view overrides_source) {
  BindingTables tables;
  const std::string psrc(part_joints_source), osrc(overrides_source);
  if (!part_joints_json.empty()) {
    const Json root = parse_json(part_joints_json, psrc);
    if (!root.is_object() || !root.contains("parts") || !root["parts"].is_object())
      throw LoadError(psrc + ": expected an object with a 'parts' object");
    check_keys(root, {"parts"}, psrc);
    for (const auto& [part, joint] : root["parts"].items()) {
      const std::string where = psrc + ": parts." + part;
      if (!known_part_name(part)) throw LoadError(where + ": unknown part (not one of the paper's 53)");
      if (!joint.is_string()) throw LoadError(where + ": the joint must be a name string");
      const std::string name = joint.get<std::string>();
      if (!known_joint_name(name)) throw LoadError(where + ": unknown joint '" + name + "'");
      tables.part_joints.emplace_back(part, name);
    }
  }
  if (!overrides_json.empty()) {
    const Json root = parse_json(overrides_json, osrc);
    if (!root.is_object() || !root.contains("overrides") || !root["overrides"].is_array())
      throw LoadError(osrc + ": expected an object with an 'overrides' array");
    check_keys(root, {"overrides", "step2_radii"}, osrc);
    const Json& list = root["overrides"];
    for (std::size_t i = 0; i < list.size(); ++i) tables.overrides.push_back(parse_selection(list[i], osrc, i));
    if (root.contains("step2_radii")) {
      const Json& radii = root["step2_radii"];
      if (!radii.is_object()) throw LoadError(osrc + ": 'step2_radii' must be an object of joint names to metres");
      for (const auto& [joint, radius] : radii.items()) {
        const std::string where = osrc + ": step2_radii." + joint;
        if (!known_joint_name(joint)) throw LoadError(where + ": unknown joint");
        if (!radius.is_number() || !std::isfinite(radius.get<double>()) || radius.get<double>() <= 0.0 ||
            radius.get<double>() > 1.0)
          throw LoadError(where + ": the radius must be a number of metres in (0, 1]");
        tables.step2_radii.emplace_back(joint, radius.get<float>());
      }
    }
  }
  return tables;
}

const BindingTables& default_binding_tables() {
  static const BindingTables tables = [] {
    const auto parts = embedded::find("data/part_joints.json");
    const auto overrides = embedded::find("data/binding_overrides.json");
    if (!parts || !overrides) throw LoadError("<embedded>: binding tables missing from the build");
    return load_binding_tables(*parts, *overrides, "<embedded>/data/part_joints.json",
                               "<embedded>/data/binding_overrides.json");
  }();
  return tables;
}

const BindingTables& makehuman_binding_tables() {
  static const BindingTables tables = [] {
    const auto extra = embedded::find("data/makehuman_binding_overrides.json");
    if (!extra) throw LoadError("<embedded>: data/makehuman_binding_overrides.json missing from the build");
    BindingTables t = default_binding_tables();
    BindingTables more = load_binding_tables("", *extra, "", "<embedded>/data/makehuman_binding_overrides.json");
    t.overrides.insert(t.overrides.end(), more.overrides.begin(), more.overrides.end());
    t.step2_radii.insert(t.step2_radii.end(), more.step2_radii.begin(), more.step2_radii.end());
    return t;
  }();
  return tables;
}

namespace {

using OrderedJson = nlohmann::ordered_json;  // keys in the order a reader expects (name first), not sorted

// The shortest decimal that reads back as `f` ("0.94", not the double 0.9399999976158142), as a JSON number. The
// loader parses a double and narrows it to float; when that double rounding could land elsewhere (rare), the
// exact double value of f is written instead, so a round trip is always exact.
OrderedJson float_json(float f) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, f).ptr;
  double d = 0.0;
  std::from_chars(text, end, d);
  return static_cast<float>(d) == f ? d : static_cast<double>(f);
}

OrderedJson vec3_json(const glm::vec3& v) { return OrderedJson::array({float_json(v.x), float_json(v.y), float_json(v.z)}); }

// Two-space indentation like nlohmann's dump(2), except that arrays of numbers and strings fill lines up to
// `kWidth` columns: dump(2) puts each of an edit's hundreds of vertex ids on its own line.
void write_pretty(const OrderedJson& j, std::size_t indent, std::string& out) {
  constexpr std::size_t kWidth = 110;
  const std::string pad(indent + 2, ' ');
  if (j.is_object() && !j.empty()) {
    out += "{\n";
    std::size_t i = 0;
    for (const auto& [key, value] : j.items()) {
      out += pad + OrderedJson(key).dump() + ": ";
      write_pretty(value, indent + 2, out);
      out += ++i < j.size() ? ",\n" : "\n";
    }
    out += std::string(indent, ' ') + "}";
  } else if (j.is_array() && !j.empty()) {
    const bool flat = std::none_of(j.begin(), j.end(), [](const OrderedJson& e) { return e.is_structured(); });
    if (flat) {
      std::string line = "[";
      for (std::size_t i = 0; i < j.size(); ++i) line += (i ? ", " : "") + j[i].dump();
      const std::size_t column = out.size() - std::min(out.size(), out.rfind('\n') + 1);
      if (column + line.size() + 1 <= kWidth) {
        out += line + "]";
        return;
      }
    }
    out += "[\n" + pad;
    std::size_t column = pad.size();
    for (std::size_t i = 0; i < j.size(); ++i) {
      std::string item;
      if (flat) {
        item = j[i].dump();
      } else {
        write_pretty(j[i], indent + 2, item);
      }
      if (i > 0 && (!flat || column + 2 + item.size() > kWidth)) {
        out += ",\n" + pad;
        column = pad.size();
      } else if (i > 0) {
        out += ", ";
        column += 2;
      }
      out += item;
      column += item.size();
    }
    out += "\n" + std::string(indent, ' ') + "]";
  } else {
    out += j.dump();
  }
}

}  // namespace

std::string binding_overrides_json(std::span<const SkinSelection> overrides,
                                   std::span<const std::pair<std::string, float>> step2_radii) {
  OrderedJson list = OrderedJson::array();
  for (const SkinSelection& s : overrides) {
    OrderedJson e;
    e["name"] = s.name;
    switch (s.kind) {
      case SkinSelection::Kind::Vertices:
        e["vertices"] = s.vertices;
        if (s.mesh_vertices != 0) e["mesh_vertices"] = s.mesh_vertices;
        break;
      case SkinSelection::Kind::Sphere:
        e["sphere"] = {{"center", vec3_json(s.center)}, {"radius", float_json(s.radius)}};
        break;
      case SkinSelection::Kind::Box:
        e["box"] = {{"min", vec3_json(s.box_min)}, {"max", vec3_json(s.box_max)}};
        break;
    }
    if (!s.parts.empty()) e["parts"] = s.parts;
    if (!s.joints.empty()) e["joints"] = s.joints;
    e["blend"] = s.blend == SkinSelection::Blend::NearestTwo ? "nearest_two"
                 : s.blend == SkinSelection::Blend::Harmonic ? "harmonic"
                                                              : "parent";
    e["falloff_m"] = float_json(s.falloff_m);
    list.push_back(std::move(e));
  }
  OrderedJson root;
  root["_doc"] = {"Step-3 skin binding overrides, applied in order after the part table (steps 1-2).",
                  "Format and meaning of every field: the _doc of data/binding_overrides.json."};
  if (!step2_radii.empty()) {
    OrderedJson radii = OrderedJson::object();
    for (const auto& [joint, radius] : step2_radii) radii[joint] = float_json(radius);
    root["step2_radii"] = std::move(radii);
  }
  root["overrides"] = std::move(list);
  std::string out;
  write_pretty(root, 0, out);
  return out + "\n";
}

BindingTables load_binding_overrides_file(const std::filesystem::path& path, const BindingTables& base) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw LoadError(path.string() + ": cannot open file");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw LoadError(path.string() + ": read error");
  // load_binding_tables takes empty text as "no entries"; an empty file named on purpose is a mistake instead.
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw LoadError(path.string() + ": empty file (expected {\"overrides\": [...]})");
  BindingTables tables = load_binding_tables("", text, "", path.string());
  tables.part_joints = base.part_joints;
  // The body's step-2 radii stay (they are the body's, as its part table is); the file's own come after and win.
  tables.step2_radii.insert(tables.step2_radii.begin(), base.step2_radii.begin(), base.step2_radii.end());
  return tables;
}

BindingStats binding_stats(const SkinBinding& binding) {
  BindingStats s;
  s.vertices = binding.vertex_count();
  for (std::size_t v = 0; v < binding.vertex_count(); ++v) {
    const int n = binding.influence_count(v);
    s.one_joint += n == 1;
    s.two_joints += n == 2;
    s.more_joints += n > 2;
  }
  return s;
}

SkinBinding bind_three_step(const Mesh& mesh, const Skeleton& skeleton, const BindingTables& tables,
                            const BindingOptions& options) {
  if (mesh.part.empty() && mesh.part_names.size() != 1)
    throw std::invalid_argument("bind_three_step: mesh '" + mesh.name + "' has no part ids");
  std::vector<int> part_joint(mesh.part_names.size(), -1);
  std::vector<bool> part_used(mesh.part_names.size(), mesh.part.empty());
  for (std::uint16_t p : mesh.part) part_used[p] = true;
  for (std::size_t p = 0; p < mesh.part_names.size(); ++p) {
    if (!part_used[p]) continue;
    const std::string* joint = tables.joint_of_part(mesh.part_names[p]);
    if (!joint)
      throw std::invalid_argument("bind_three_step: part '" + mesh.part_names[p] + "' has no joint in the table");
    part_joint[p] = skeleton.find_joint(*joint);
    if (part_joint[p] < 0)
      throw std::invalid_argument("bind_three_step: part '" + mesh.part_names[p] + "' maps to joint '" + *joint +
                                  "', which skeleton '" + skeleton.name + "' lacks");
  }

  SkinBinding binding;
  binding.joints.assign(mesh.vertex_count(), {});
  binding.weights.assign(mesh.vertex_count(), {});
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    binding.joints[v][0] = static_cast<std::int16_t>(part_joint[mesh.part.empty() ? 0 : mesh.part[v]]);
    binding.weights[v][0] = 1.0f;
  }
  for (BlendJoint bj : options.blend_joints) {
    for (const auto& [joint, radius] : tables.step2_radii)  // the last entry for a joint wins, as overrides do
      if (joint == bj.joint) bj.radius_m = radius;
    blend_near_joint(bj, mesh, skeleton, options.step2_weights, binding);
  }
  if (options.apply_overrides)
    for (const SkinSelection& s : tables.overrides) apply_selection(s, mesh, skeleton, binding);
  return binding;
}

// ---- Bone heat ---------------------------------------------------------------------------------------------------

namespace {

struct Segment {
  glm::dvec3 a, b;
  int joint;
};

double point_segment_distance(const glm::dvec3& p, const Segment& s) {
  const glm::dvec3 ab = s.b - s.a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(p - s.a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (s.a + t * ab));
}

// Symmetric sparse matrix in CSR form, diagonal kept apart.
struct SparseSym {
  std::vector<std::size_t> offsets;
  std::vector<std::uint32_t> cols;
  std::vector<double> values;
  std::vector<double> diagonal;

  void multiply(const std::vector<double>& x, std::vector<double>& y) const {
    for (std::size_t r = 0; r + 1 < offsets.size(); ++r) {
      double s = diagonal[r] * x[r];
      for (std::size_t k = offsets[r]; k < offsets[r + 1]; ++k) s += values[k] * x[cols[k]];
      y[r] = s;
    }
  }
};

// Jacobi-preconditioned conjugate gradients from x's initial value. Chosen over Gauss-Seidel, which converges
// in O(n) sweeps on a diffusion this wide (the heat term is weak where the surface is far from its bone).
void solve_cg(const SparseSym& A, const std::vector<double>& b, std::vector<double>& x, double tolerance,
              int max_iterations) {
  const std::size_t n = b.size();
  std::vector<double> r(n), z(n), p(n), q(n);
  A.multiply(x, q);
  double b_norm = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = b[i] - q[i];
    b_norm += b[i] * b[i];
  }
  b_norm = std::sqrt(b_norm);
  if (b_norm == 0.0) {
    std::fill(x.begin(), x.end(), 0.0);
    return;
  }
  double rz = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    z[i] = r[i] / A.diagonal[i];
    p[i] = z[i];
    rz += r[i] * z[i];
  }
  for (int it = 0; it < max_iterations; ++it) {
    double r_norm = 0.0;
    for (std::size_t i = 0; i < n; ++i) r_norm += r[i] * r[i];
    if (std::sqrt(r_norm) <= tolerance * b_norm) break;
    A.multiply(p, q);
    double pq = 0.0;
    for (std::size_t i = 0; i < n; ++i) pq += p[i] * q[i];
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    double rz_next = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
      z[i] = r[i] / A.diagonal[i];
      rz_next += r[i] * z[i];
    }
    const double beta = rz_next / rz;
    rz = rz_next;
    for (std::size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
  }
}

}  // namespace

SkinBinding bind_automatic(const Mesh& mesh, const Skeleton& skeleton, const AutoBindOptions& options) {
  const std::size_t n = mesh.vertex_count();
  const std::size_t joints = skeleton.joint_count();
  if (joints == 0) throw std::invalid_argument("bind_automatic: skeleton has no joints");

  // Bones: a joint rotates the segments from its centre to its children's centres.
  std::vector<Segment> segments;
  std::vector<bool> has_child(joints, false);
  for (std::size_t j = 0; j < joints; ++j)
    if (int p = skeleton.parents[j]; p >= 0) {
      segments.push_back({glm::dvec3(skeleton.centers[p]), glm::dvec3(skeleton.centers[j]), p});
      has_child[p] = true;
    }
  for (std::size_t j = 0; j < joints; ++j) {
    if (has_child[j]) continue;
    const glm::dvec3 c(skeleton.centers[j]);
    glm::dvec3 tip = c;
    for (const SkeletonSite& site : skeleton.sites)
      if (site.joint == static_cast<int>(j) && glm::length(glm::dvec3(site.position) - c) > glm::length(tip - c))
        tip = glm::dvec3(site.position);
    // No site: carry on along the parent bone for half its length. A point bone at the centre would sit exactly
    // on the end of the parent's segment, so every vertex beyond it would tie between the two joints.
    if (tip == c && skeleton.parents[j] >= 0) tip = c + 0.5 * (c - glm::dvec3(skeleton.centers[skeleton.parents[j]]));
    segments.push_back({c, tip, static_cast<int>(j)});
  }

  // Nearest bone per vertex; exact ties (a vertex on the bisector plane of two bones) share the heat source.
  std::vector<double> heat_distance(n);
  std::vector<std::vector<int>> nearest(n);
  for (std::size_t v = 0; v < n; ++v) {
    const glm::dvec3 p(mesh.positions[v]);
    double best = std::numeric_limits<double>::max();
    for (const Segment& s : segments) best = std::min(best, point_segment_distance(p, s));
    for (const Segment& s : segments)
      if (point_segment_distance(p, s) <= best * (1.0 + 1e-9) &&
          std::find(nearest[v].begin(), nearest[v].end(), s.joint) == nearest[v].end())
        nearest[v].push_back(s.joint);
    heat_distance[v] = std::max(best, 1e-4);
  }

  // Cotangent Laplacian and barycentric vertex areas.
  std::vector<double> area;
  const CotangentEdges edges = cotangent_edges(mesh, {}, &area);
  SparseSym K;
  K.offsets.assign(1, 0);
  K.diagonal.assign(n, 0.0);
  std::vector<double> screen(n, 0.0);  // A_v H_v
  for (std::size_t v = 0; v < n; ++v) {
    if (area[v] <= 0.0) {
      K.diagonal[v] = 1.0;  // no surface around it: the solve returns its heat source unchanged
    } else {
      screen[v] = area[v] * options.heat / (heat_distance[v] * heat_distance[v]);
      K.diagonal[v] = screen[v];
      for (const auto& [u, w] : edges[v]) {
        // cotangent_edges clamps obtuse pairs' negative sums at 0, which keeps the matrix an M-matrix, so weights
        // obey the maximum principle (no negative lobes) at the price of a slightly less exact Laplacian.
        if (w == 0.0) continue;
        K.cols.push_back(u);
        K.values.push_back(-w);
        K.diagonal[v] += w;
      }
    }
    K.offsets.push_back(K.cols.size());
  }

  // One solve per joint that is some vertex's nearest bone; other joints' weights are exactly zero.
  std::vector<int> solved;
  {
    std::vector<bool> used(joints, false);
    for (const auto& list : nearest)
      for (int j : list) used[j] = true;
    for (std::size_t j = 0; j < joints; ++j)
      if (used[j]) solved.push_back(static_cast<int>(j));
  }
  std::vector<std::vector<double>> weight(solved.size());
  tbb::parallel_for(std::size_t(0), solved.size(), [&](std::size_t s) {
    const int j = solved[s];
    std::vector<double> b(n), x(n);
    for (std::size_t v = 0; v < n; ++v) {
      const auto& list = nearest[v];
      const double p =
          std::find(list.begin(), list.end(), j) != list.end() ? 1.0 / static_cast<double>(list.size()) : 0.0;
      b[v] = area[v] > 0.0 ? screen[v] * p : p;
      x[v] = p;
    }
    solve_cg(K, b, x, options.tolerance, options.max_iterations);
    weight[s] = std::move(x);
  });

  SkinBinding binding;
  binding.joints.assign(n, {});
  binding.weights.assign(n, {});
  for (std::size_t v = 0; v < n; ++v) {
    std::vector<Influence> in;
    for (std::size_t s = 0; s < solved.size(); ++s)
      if (weight[s][v] >= options.min_weight) in.push_back({solved[s], weight[s][v]});
    if (in.empty()) in.push_back({nearest[v].front(), 1.0});
    set_influences(binding, v, std::move(in));
  }
  return binding;
}

}  // namespace strata
