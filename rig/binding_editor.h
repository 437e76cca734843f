#pragma once
// The binding editor's core: the paper's manual step 3 (section 6, "the vertices are selected with the mouse and
// bound to the selected joint"), headless and testable; `strata view`'s panel draws and drives it.
//
//   pick_ray / pick_vertex      the vertex under the cursor (nearest triangle hit, then its nearest corner)
//   visible_vertices            which vertices the camera sees (software depth buffer), so a box or brush does
//                               not grab the back of the body through the front
//   select_rect / select_brush  screen-space selection with Replace / Add / Subtract
//   BindingEditor               binds the selection to a joint and its parent, undo, weight heat colours, and
//                               saves the edits as a binding overrides file that reproduces them exactly
//
// An edit is stored as a SkinSelection of explicit vertex ids (Kind::Vertices) with mesh_vertices set to the
// edited mesh's vertex count, so one overrides file holds edits of several body levels and each applies only to
// its own level. A sphere or box (which would carry over to every level) was rejected: the user picks vertices,
// and a region that approximates the pick would bind vertices the user did not pick.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "components/mesh.h"
#include "components/skeleton.h"
#include "rig/binding.h"

namespace strata {

struct PickRay {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // unit length
};

// The ray through a pixel (x right, y DOWN, origin top-left of a viewport of `viewport` pixels; continuous
// coordinates, so the centre of pixel (i, j) is (i + 0.5, j + 0.5), as a mouse position reads) for a camera whose
// clip transform is `view_projection` (OpenGL clip space, depth -1..1). The origin lies on the near plane.
// Throws std::invalid_argument for a non-positive viewport or a singular or non-finite view_projection.
PickRay pick_ray(const glm::mat4& view_projection, glm::vec2 pixel, glm::ivec2 viewport);

// The mesh as the user sees it: world-space positions in mesh vertex order and its triangles.
struct EditMesh {
  std::span<const glm::vec3> positions;
  std::span<const std::uint32_t> triangles;
};

// The vertex of the nearest triangle hit by `ray` that is closest to the hit point; nullopt on a miss.
// Degenerate and non-finite triangles are skipped; both faces count (the nearest surface is what the user sees).
// Throws std::invalid_argument when a triangle index is out of range.
std::optional<std::uint32_t> pick_vertex(const EditMesh& mesh, const PickRay& ray);

// Per vertex 1 when it projects inside the viewport, in front of the camera (inside the near and far planes), and
// no triangle covers it nearer to the camera (a software depth buffer of the triangles at viewport resolution;
// tolerance relative to depth so a vertex is not hidden by its own triangles). What box and brush select use
// unless "select through". Each vertex is tested against the farthest of the four pixel centres around it, so
// a part only a few pixels thick (fingers, or a hand 8 m away) can show its far side; a trunk or a limb in a
// normal view cannot. A singular view_projection sees nothing (all 0). Throws std::invalid_argument for a
// non-positive viewport or an index out of range. About 6 ms for level 0 at 1280x720 on one core of the dev VM
// (bench/editor_bench.cpp), against 0.1 ms for a brush step: compute it when the camera or the pose changes,
// not per brush step.
std::vector<std::uint8_t> visible_vertices(const EditMesh& mesh, const glm::mat4& view_projection,
                                           glm::ivec2 viewport);

enum class SelectOp : std::uint8_t { Replace, Add, Subtract };

class VertexSelection {
 public:
  explicit VertexSelection(std::size_t vertex_count = 0);
  std::size_t vertex_count() const { return selected_.size(); }
  std::size_t count() const { return count_; }  // selected
  bool contains(std::uint32_t v) const { return v < selected_.size() && selected_[v] != 0; }
  void clear();
  // Throws std::out_of_range for v >= vertex_count().
  void set(std::uint32_t v, bool on);
  std::vector<std::uint32_t> ids() const;  // ascending

 private:
  std::vector<std::uint8_t> selected_;
  std::size_t count_ = 0;
};

// Box (pixel corners in any order, edges included) and brush (circle, rim included) selection in screen space,
// of the vertices in front of the camera and inside the viewport; `visible` from visible_vertices, or empty to
// select through the mesh. Replace clears the selection first, Add sets, Subtract clears what is inside.
// Throws std::invalid_argument when the selection's, visible's (if not empty) and the mesh's vertex counts differ.
void select_rect(const EditMesh& mesh, const glm::mat4& view_projection, glm::ivec2 viewport, glm::vec2 corner_a,
                 glm::vec2 corner_b, std::span<const std::uint8_t> visible, SelectOp op, VertexSelection& selection);
void select_brush(const EditMesh& mesh, const glm::mat4& view_projection, glm::ivec2 viewport, glm::vec2 centre,
                  float radius_px, std::span<const std::uint8_t> visible, SelectOp op, VertexSelection& selection);

// An editing session of one mesh level's binding. Picking happens on whatever positions the caller shows
// (rest or posed); the weights are always computed on the REST mesh, exactly as the overrides file will be
// applied when it is loaded again, so what the editor shows is what the file reproduces: binding the mesh with
// load_binding_overrides_file(saved file, tables) gives binding() exactly, provided the binding passed in was
// bind_three_step(rest_mesh, skeleton, tables).
class BindingEditor {
 public:
  // `tables` are the tables the current binding was made with (their overrides are kept when saving). The mesh
  // and skeleton are copied: the viewer may rebuild its body from binding() while the session goes on.
  // Throws std::invalid_argument when the binding's and the mesh's vertex counts differ.
  BindingEditor(const Mesh& rest_mesh, const Skeleton& skeleton, SkinBinding binding, BindingTables tables);

  VertexSelection& selection() { return selection_; }
  const VertexSelection& selection() const { return selection_; }

  // Binds the selected vertices to `joint` and its parent with inverse-distance weights (rest pose), by adding
  // a SkinSelection {Kind::Vertices, ids, mesh_vertices = mesh vertex count, joints = {joint name},
  // blend = Parent, name = `name` or "edit N"} and applying it with apply_selection. Returns false (and changes
  // nothing) when the selection is empty or not of this mesh's size, or the joint is invalid: out of range, or
  // a name the overrides file cannot carry (not an H-Anim joint, or not resolving back to `joint`). A root joint
  // (no parent) binds rigidly to it. The selection itself is kept.
  bool bind_selection(int joint, std::string name = {});
  bool undo();  // removes the last bind_selection, restoring the binding bit-exactly; false when none
  std::size_t edit_count() const { return undo_.size(); }
  const SkinBinding& binding() const { return binding_; }
  const BindingTables& tables() const { return tables_; }  // original overrides + the edits, in order
  const Mesh& rest_mesh() const { return mesh_; }

  // Per vertex RGBA8 (0xAABBGGRR, i.e. bytes R,G,B,A in memory) heat colour of `joint`'s weight (0 blue ..
  // 1 red through green/yellow); selected vertices drawn in a highlight colour (white) when `show_selection`.
  // A joint out of range has weight 0 everywhere. Throws std::invalid_argument when rgba is not one per vertex.
  void weight_colors(int joint, bool show_selection, std::span<std::uint32_t> rgba) const;

  // Writes binding_overrides_json(tables().overrides, tables().step2_radii) atomically (io/atomic_file.h). Throws on I/O failure.
  void save(const std::filesystem::path& path) const;

 private:
  // What one bind_selection overwrote: the previous influences of exactly the vertices it rebound.
  struct Edit {
    std::vector<std::uint32_t> vertices;
    std::vector<std::array<std::int16_t, kMaxInfluences>> joints;
    std::vector<std::array<float, kMaxInfluences>> weights;
  };

  Mesh mesh_;
  Skeleton skeleton_;
  SkinBinding binding_;
  BindingTables tables_;
  VertexSelection selection_;
  std::vector<Edit> undo_;
};

// The heat colour of a weight (clamped to 0..1, NaN as 0) as BindingEditor::weight_colors packs it.
std::uint32_t weight_heat_rgba(float weight);
inline constexpr std::uint32_t kSelectionRgba = 0xFFFFFFFFu;  // white, opaque

}  // namespace strata
