#pragma once
// Skin binding: which joints move each skin vertex, and how much (the weights of the paper's equation 4).
//
// Two binders, both producing a SkinBinding (components/mesh.h) of at most four influences whose weights sum to 1:
//
//   bind_three_step  the paper's method (Memisoglu/Gudukbay, sections 5-6):
//     1. every vertex of a skin part goes to the part's joint (data/part_joints.json);
//     2. vertices within a per-joint distance of an elbow or knee are also bound to the adjacent joint
//        (the elbow itself for an upper-arm vertex, the shoulder for a forearm vertex);
//     3. hand-picked selections (data/binding_overrides.json) are re-bound to the closest joint and its parent
//        with inverse-distance weights, or (beyond the paper) interpolated harmonically from the binding around
//        them (rig/harmonic_weights.h).
//   bind_automatic   bone heat (Baran & Popovic 2007): per joint, a heat-diffusion solve over the surface gives
//     smooth weights with no table and no manual step.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "components/mesh.h"
#include "components/skeleton.h"

namespace strata {

// One step-3 selection (see data/binding_overrides.json for the file format and the meaning of each field).
struct SkinSelection {
  enum class Kind : std::uint8_t { Vertices, Sphere, Box };
  // Harmonic: the selection's weights are interpolated from the vertices around it (rig/harmonic_weights.h);
  // `joints` and `falloff_m` do not apply.
  enum class Blend : std::uint8_t { Parent, NearestTwo, Harmonic };
  std::string name;
  Kind kind = Kind::Vertices;
  std::vector<std::uint32_t> vertices;  // Kind::Vertices
  // Kind::Vertices: 0 = the ids fit any mesh; N > 0 = they belong to a mesh of N vertices, and the entry is
  // skipped for a mesh of another count. One overrides file serves every level of a body (the shipped body has
  // three levels and a cage, all of different counts), and an id list of one level means nothing on another.
  std::uint32_t mesh_vertices = 0;
  glm::vec3 center{0.0f};               // Kind::Sphere
  float radius = 0.0f;                  // Kind::Sphere
  glm::vec3 box_min{0.0f};              // Kind::Box
  glm::vec3 box_max{0.0f};              // Kind::Box
  std::vector<std::string> parts;       // empty: every part
  std::vector<std::string> joints;      // empty: every joint of the skeleton
  Blend blend = Blend::Parent;
  float falloff_m = 0.0f;               // 0: replace the binding; > 0: fade into it near the selection's edge
};

struct BindingTables {
  std::vector<std::pair<std::string, std::string>> part_joints;  // part name -> joint name, in file order
  std::vector<SkinSelection> overrides;                          // applied in order
  // Step-2 radii (m) this body sets for named joints in place of BindingOptions::blend_joints' (the overrides
  // file's "step2_radii" object): a body whose knee is thicker than the default's needs a wider blend.
  std::vector<std::pair<std::string, float>> step2_radii;

  // Joint name of a part, nullptr when the table has no entry.
  const std::string* joint_of_part(std::string_view part) const;
};

// Parses the two JSON tables. Throws LoadError "SOURCE: <entry>: reason" naming the file and the entry at fault:
// malformed JSON, a part that is not one of the paper's 53 (paper_part_names), a joint name that is not an
// H-Anim joint, a duplicate part, a malformed selection. Either text may be empty (no entries).
BindingTables load_binding_tables(std::string_view part_joints_json, std::string_view overrides_json,
                                  std::string_view part_joints_source = "part_joints.json",
                                  std::string_view overrides_source = "binding_overrides.json");
// The inverse of the overrides half of load_binding_tables: a pretty-printed {"_doc": ..., "step2_radii": {...},
// "overrides": [...]} that loads back to the same selections and radii field by field (floats are written so they
// parse to the same float; no "step2_radii" key when there are none).
std::string binding_overrides_json(std::span<const SkinSelection> overrides,
                                   std::span<const std::pair<std::string, float>> step2_radii = {});

// `base`'s part table and step-2 radii with the overrides of the file at `path` in place of base's overrides
// (the file's own step2_radii, if any, after base's) (`strata crowd
// --binding-overrides`, the binding editor's saved files). Throws LoadError naming the file (and the entry).
BindingTables load_binding_overrides_file(const std::filesystem::path& path, const BindingTables& base);

// The shipped tables (data/part_joints.json, data/binding_overrides.json, embedded), parsed once. Throws LoadError
// when the build did not embed them (STRATA_EMBEDDED_FILES).
const BindingTables& default_binding_tables();
// The MakeHuman-derived body's tables (rig/makehuman_body.h): the shipped ones with the selections of
// data/makehuman_binding_overrides.json applied after theirs.
const BindingTables& makehuman_binding_tables();

// Step-2 threshold of one joint: vertices closer than radius_m to its centre blend it with the adjacent joint.
struct BlendJoint {
  std::string joint;
  float radius_m = 0.0f;
};

enum class Step2Weights : std::uint8_t {
  // The paper's rule, literally: weights inversely proportional to the distances to the two joint centres. It
  // is continuous across the part boundary but jumps at the threshold sphere (a weight of ~0.2-0.7 drops to 0).
  InverseDistance,
  // Default. A smoothstep along the parent bone's axis, 1/2 at the joint, whose half-width at each vertex is the
  // sphere's half-chord at that vertex's distance from the axis: the blend reaches 0/1 exactly on the sphere,
  // so the weights are continuous everywhere and C1 inside, and still give every vertex in the sphere two joints.
  AxialSmoothstep,
};

struct BindingOptions {
  // Defaults for an adult of ~1.75 m: a forearm is ~0.04 m in radius at the elbow and a knee ~0.055 m, so these
  // radii blend a band of about +-0.055 m (elbow) and +-0.07 m (knee) along the limb.
  std::vector<BlendJoint> blend_joints = {
      {"l_elbow", 0.07f}, {"r_elbow", 0.07f}, {"l_knee", 0.09f}, {"r_knee", 0.09f}};
  Step2Weights step2_weights = Step2Weights::AxialSmoothstep;
  bool apply_overrides = true;
};

// The paper's Table 1 columns for one binding.
struct BindingStats {
  std::size_t vertices = 0;
  std::size_t one_joint = 0;
  std::size_t two_joints = 0;
  std::size_t more_joints = 0;
};
BindingStats binding_stats(const SkinBinding& binding);

// Throws std::invalid_argument when a mesh part has no table entry, a table joint is missing from the skeleton,
// or the mesh has no part ids while it has more than one part name. Joint names in the tables and options that
// the skeleton lacks are errors for step 1 and skipped for steps 2 and 3 (an optional refinement).
SkinBinding bind_three_step(const Mesh& mesh, const Skeleton& skeleton, const BindingTables& tables,
                            const BindingOptions& options = {});

// Step 3 for one selection, exactly as bind_three_step applies each override: the selected vertices (of the
// selection's parts) are re-bound to their closest candidate joint and its parent (or the nearest two), with
// inverse-distance weights, faded into the previous binding by falloff_m. A Kind::Vertices selection whose
// mesh_vertices names another vertex count is skipped; an id out of range of a matching mesh throws
// std::invalid_argument naming the selection.
void apply_selection(const SkinSelection& s, const Mesh& mesh, const Skeleton& skeleton, SkinBinding& binding);

struct AutoBindOptions {
  // Heat strength c of Baran & Popovic's H = c / d^2. 1 is their value: the blend region then scales with the
  // distance from the surface to the bones, i.e. with the limb's thickness.
  float heat = 1.0f;
  // Weights below this after the solve are dropped before the top-4 cut (keeps influence counts meaningful).
  float min_weight = 0.01f;
  // Conjugate-gradient stop: relative residual, and an iteration cap per joint.
  double tolerance = 1e-7;
  int max_iterations = 4000;
};

// Bone heat. Each joint j owns the segments from its centre to each child's centre (a leaf joint: to the
// farthest site it carries, else half its parent bone's length onwards along that bone). Per joint, solves
// (L + A H) w_j = A H p_j with L the cotangent Laplacian (weights clamped at 0, so the matrix is an M-matrix and
// w stays in [0, 1]), A the vertex areas, H = heat / d^2 from the nearest segment, p_j = 1 where j owns the
// nearest segment, by Jacobi-preconditioned conjugate gradients. Nearest-bone visibility (Baran's ray test) is
// not checked: it costs a ray cast per vertex and bone, and the limbs of a standing body do not hide their own
// bones. Deterministic: the solves are independent per joint and each is sequential. About 0.1 s for an 18k-vertex
// arm on two cores.
SkinBinding bind_automatic(const Mesh& mesh, const Skeleton& skeleton, const AutoBindOptions& options = {});

}  // namespace strata
