// Google Benchmark: the binding editor's per-interaction costs on the shipped body, as `strata view` would pay
// them: a pick under the cursor, the visibility mask (once per camera change), a brush stroke step, and a bind.
// Arg = body level (0 finest .. 2). The viewport is 1280x720 and the camera frames the whole body from the front.
#include <benchmark/benchmark.h>

#include <algorithm>

#include <glm/gtc/matrix_transform.hpp>

#include "io/hanim_loader.h"
#include "rig/binding.h"
#include "rig/binding_editor.h"
#include "rig/body_rig.h"

namespace {

constexpr glm::ivec2 kViewport{1280, 720};

glm::mat4 front_camera() {
  return glm::perspective(0.8f, 1280.0f / 720.0f, 0.05f, 500.0f) *
         glm::lookAt(glm::vec3(0.0f, 0.9f, 2.6f), glm::vec3(0.0f, 0.9f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
}

const strata::BodyLevel& level(const benchmark::State& state) {
  return strata::default_bound_body()->levels[static_cast<std::size_t>(state.range(0))];
}

strata::EditMesh edit_mesh(const strata::Mesh& m) { return {m.positions, m.triangles}; }

void BM_PickVertex(benchmark::State& state) {
  const strata::Mesh& mesh = level(state).mesh;
  const strata::PickRay ray = strata::pick_ray(front_camera(), {640.0f, 300.0f}, kViewport);  // the chest
  for (auto _ : state) benchmark::DoNotOptimize(strata::pick_vertex(edit_mesh(mesh), ray));
  state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
}
BENCHMARK(BM_PickVertex)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

void BM_VisibleVertices(benchmark::State& state) {
  const strata::Mesh& mesh = level(state).mesh;
  std::size_t seen = 0;
  for (auto _ : state) {
    const std::vector<std::uint8_t> visible = strata::visible_vertices(edit_mesh(mesh), front_camera(), kViewport);
    seen = static_cast<std::size_t>(std::count(visible.begin(), visible.end(), 1));
    benchmark::DoNotOptimize(visible.data());
  }
  state.counters["visible_fraction"] = static_cast<double>(seen) / static_cast<double>(mesh.vertex_count());
}
BENCHMARK(BM_VisibleVertices)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

void BM_SelectBrush(benchmark::State& state) {
  const strata::Mesh& mesh = level(state).mesh;
  const std::vector<std::uint8_t> visible = strata::visible_vertices(edit_mesh(mesh), front_camera(), kViewport);
  strata::VertexSelection selection(mesh.vertex_count());
  for (auto _ : state)
    strata::select_brush(edit_mesh(mesh), front_camera(), kViewport, {640.0f, 300.0f}, 40.0f, visible,
                         strata::SelectOp::Add, selection);
  state.counters["selected"] = static_cast<double>(selection.count());
}
BENCHMARK(BM_SelectBrush)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

// bind_selection + undo of the brush selection above: the apply itself, the loader round trip that checks the
// entry, and the undo record.
void BM_BindSelectionAndUndo(benchmark::State& state) {
  const strata::BodyLevel& l = level(state);
  const strata::Skeleton skeleton = strata::load_default_humanoid().skeleton;
  strata::BindingEditor editor(l.mesh, skeleton, l.binding, strata::default_binding_tables());
  const std::vector<std::uint8_t> visible = strata::visible_vertices(edit_mesh(l.mesh), front_camera(), kViewport);
  strata::select_brush(edit_mesh(l.mesh), front_camera(), kViewport, {640.0f, 300.0f}, 40.0f, visible,
                       strata::SelectOp::Replace, editor.selection());
  const int joint = skeleton.find_joint("vt6");
  for (auto _ : state) {
    benchmark::DoNotOptimize(editor.bind_selection(joint));
    editor.undo();
  }
  state.counters["selected"] = static_cast<double>(editor.selection().count());
}
BENCHMARK(BM_BindSelectionAndUndo)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
