// strata report subdiv: the shipped body's cage refined to S1..S3 every frame, against skinning the paper's mesh
// levels directly. Per level: the per-frame cost of the refinement (ns per refined vertex, one core) in our
// level-by-level SoA form, in OpenSubdiv's factorised stencils with the same loop, and through
// Far::StencilTable::UpdateValues on AoS; the normals; the whole walker; and how far the refined surface lies from
// the directly skinned level-0 mesh at rest and at a flexed pose.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "io/hanim_loader.h"
#include "reference/surface_distance.h"
#include "rig/body_rig.h"
#include "rig/subdiv_refiner.h"
#include "systems/fk.h"
#include "scene/crowd.h"
#include "systems/subdiv.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

namespace Far = OpenSubdiv::Far;

struct SubdivReportOptions {
  std::string json;
  double min_batch_ms = 20.0;  // each timing batch runs at least this long; the best of `batches` is kept
  int batches = 5;
};

// Best-of-batches time of one call of `f`, in ns. The minimum, not the mean: on a shared 2-core VM the noise
// only ever adds time.
template <class F>
double time_ns(const SubdivReportOptions& o, F&& f) {
  using clock = std::chrono::steady_clock;
  std::size_t reps = 1;
  for (;;) {  // calibrate the batch size
    const auto t0 = clock::now();
    for (std::size_t r = 0; r < reps; ++r) f();
    const double ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
    if (ms >= o.min_batch_ms || reps > (1u << 24)) break;
    reps = ms <= 0.0 ? reps * 8 : std::max<std::size_t>(reps + 1, static_cast<std::size_t>(reps * 1.2 * o.min_batch_ms / ms));
  }
  double best = 1e300;
  for (int b = 0; b < o.batches; ++b) {
    const auto t0 = clock::now();
    for (std::size_t r = 0; r < reps; ++r) f();
    best = std::min(best, std::chrono::duration<double, std::nano>(clock::now() - t0).count() / static_cast<double>(reps));
  }
  return best;
}

// OpenSubdiv's own per-frame path for comparison: UpdateValues needs Clear() and AddWithWeight() on an AoS type.
struct Point3 {
  float x, y, z;
  void Clear() { x = y = z = 0.0f; }
  void AddWithWeight(const Point3& s, float w) {
    x += w * s.x;
    y += w * s.y;
    z += w * s.z;
  }
};

// Flexes the left elbow and knee by 120 deg (the pose `strata report skin` uses) on walker 0 and reruns FK.
void flex(const Skeleton& s, const WalkerLanes& lanes, SoaTable& walkers) {
  for (std::uint32_t j = 0; j < lanes.joints; ++j)
    for (int c = 0; c < 4; ++c) lanes.local_rotation[(j * 4 + c) * lanes.stride] = c == 3 ? 1.0f : 0.0f;
  for (const char* name : {"l_elbow", "l_knee"}) {
    const int joint = s.find_joint(name);
    if (joint < 0) continue;
    const JointLimits& lim = s.limits[static_cast<std::size_t>(joint)];
    const float angle = lim.present && -lim.lower.x > lim.upper.x ? -2.0944f : 2.0944f;
    const glm::quat q = glm::angleAxis(angle, glm::vec3(1, 0, 0));
    const float xyzw[4] = {q.x, q.y, q.z, q.w};
    for (int c = 0; c < 4; ++c) lanes.local_rotation[(static_cast<std::size_t>(joint) * 4 + c) * lanes.stride] = xyzw[c];
  }
  run_or_throw(make_fk_job(s, walkers), "fk");
}

int run_subdiv_report(const SubdivReportOptions& o) {
  if (!check_outputs("report subdiv", {{"--json", o.json}})) return kExitFailure;
  // One core: every number is per core, like the skin benchmarks.
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  try {
    Rig rig = to_rig(load_default_humanoid());
    rig.body = default_bound_body();
    const Body& body = *rig.body;
    if (!body.cage) throw std::runtime_error("the default body has no cage");
    const Skeleton skeleton = rig.skeleton;
    Crowd scene(std::move(rig));
    CrowdConfig config;
    config.walkers = 1;
    config.motion = MotionSource::Walk;
    spawn_crowd(scene, config);
    set_detail_level(scene, DetailLevel::none());
    Profiler profiler(8, false);
    for (int f = 0; f < 24; ++f) step(scene, 1.0f / 60.0f, profiler);  // mid-stride: a walking pose

    nlohmann::json out;
    out["threads"] = 1;
    out["cage"] = {{"vertices", body.cage->mesh.vertex_count()}, {"triangles", body.cage->mesh.triangle_count()},
                   {"scheme", "loop"}, {"boundary", "edge_and_corner"}};

    // Route 1: skin a mesh level directly.
    nlohmann::json routes = nlohmann::json::array();
    std::vector<std::vector<float>> level_out(body.levels.size());
    std::vector<std::size_t> level_stride(body.levels.size());
    std::printf("%-6s %9s %10s %13s %11s\n", "route", "vertices", "triangles", "walker us", "ns/vertex");
    for (std::size_t l = 0; l < body.levels.size(); ++l) {
      const SkinLayout layout = make_skin_layout(body.levels[l]);
      level_stride[l] = pad_to_lanes(layout.vertex_count);
      level_out[l].assign(6 * level_stride[l], 0.0f);
      const SkinOutput so = skin_output_in(level_out[l].data(), level_stride[l]);
      const SkinWalkerJob job = make_skin_walker_job(layout, scene.table(initial_slot(scene)), 0, so);
      const double ns = time_ns(o, [&] { run_or_throw(job, "skin"); });
      routes.push_back({{"route", "skin level " + std::to_string(l)}, {"level", std::to_string(l)},
                        {"vertices", layout.vertex_count}, {"triangles", layout.triangles.size() / 3},
                        {"walker_us", ns / 1000.0}, {"ns_per_vertex", ns / layout.vertex_count}});
      std::printf("%-6s %9u %10zu %13.1f %11.2f\n", std::to_string(l).c_str(), layout.vertex_count,
                  layout.triangles.size() / 3, ns / 1000.0, ns / layout.vertex_count);
    }

    // Route 2: skin the cage and refine it.
    nlohmann::json levels = nlohmann::json::array();
    bool refine_ok = true;
    const std::size_t cage_n = body.cage->mesh.vertex_count();
    const std::size_t cage_stride = pad_to_lanes(cage_n);
    std::vector<float> cage_out(6 * cage_stride);
    for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
      const auto t0 = std::chrono::steady_clock::now();
      const SubdivSurface surface = make_subdiv_surface(*body.cage, depth);
      const double setup_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const SubdivSurface factorised = make_subdiv_surface(*body.cage, depth, StencilForm::Factorised);
      const std::size_t n = surface.vertex_count, stride = pad_to_lanes(n);
      std::vector<float> refined(6 * stride);
      const SkinOutput ro = skin_output_in(refined.data(), stride);
      const SkinOutput co = skin_output_in(cage_out.data(), cage_stride);
      run_or_throw(make_skin_walker_job(surface.cage_layout, scene.table(initial_slot(scene)), 0, co), "skin");

      // Level by level (the per-frame path), with its intermediate levels in scratch.
      std::vector<std::vector<float>> scratch;
      for (const SubdivStencils& s : surface.steps) scratch.emplace_back(3 * pad_to_lanes(s.rows()));
      auto refine = [&] {
        const float *sx = co.px, *sy = co.py, *sz = co.pz;
        for (std::size_t k = 0; k < surface.steps.size(); ++k) {
          const std::size_t st = pad_to_lanes(surface.steps[k].rows());
          float* d = scratch[k].data();
          apply_subdiv_stencils(surface.steps[k], sx, sy, sz, d, d + st, d + 2 * st);
          sx = d, sy = d + st, sz = d + 2 * st;
        }
      };
      const double refine_ns = time_ns(o, refine);
      const double factorised_ns = time_ns(o, [&] {
        apply_subdiv_stencils(factorised.steps.front(), co.px, co.py, co.pz, ro.px, ro.py, ro.pz);
      });
      // Far's UpdateValues on AoS, cage in its original vertex order.
      std::unique_ptr<Far::TopologyRefiner> refiner = make_cage_refiner(body.cage->mesh);
      refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(depth));
      Far::StencilTableFactoryReal<float>::Options so;
      so.generateIntermediateLevels = false;
      so.generateOffsets = true;
      std::unique_ptr<const Far::StencilTableReal<float>> table(Far::StencilTableFactoryReal<float>::Create(*refiner, so));
      std::vector<Point3> cage_aos(cage_n), refined_aos(n), far_aos(n);
      for (std::size_t i = 0; i < cage_n; ++i)
        cage_aos[surface.cage_layout.original[i]] = {co.px[i], co.py[i], co.pz[i]};
      const double far_ns = time_ns(o, [&] { table->UpdateValues(cage_aos.data(), far_aos.data()); });
      for (std::size_t i = 0; i < n; ++i) refined_aos[i] = far_aos[surface.opensubdiv_vertex[i]];  // our numbering
      // The three forms agree (within float rounding).
      refine();
      double form_gap = 0.0;
      {
        const SubdivStencils& last = surface.steps.back();
        const std::size_t st = pad_to_lanes(last.rows());
        const float* d = scratch.back().data();
        for (std::size_t i = 0; i < n; ++i)
          form_gap = std::max({form_gap, std::abs(double(d[i]) - refined_aos[i].x),
                               std::abs(double(d[st + i]) - refined_aos[i].y),
                               std::abs(double(d[2 * st + i]) - refined_aos[i].z)});
      }
      const double normals_ns = time_ns(o, [&] {
        area_weighted_normals(surface.triangles, n, ro.px, ro.py, ro.pz, ro.nx, ro.ny, ro.nz);
      });
      const SubdivWalkerJob walker_job = make_subdiv_walker_job(surface, scene.table(initial_slot(scene)), 0, ro);
      const double walker_ns = time_ns(o, [&] { run_or_throw(walker_job, "subdiv"); });
      const double per_v = refine_ns / static_cast<double>(n);
      refine_ok = refine_ok && per_v <= 30.0;
      levels.push_back({{"level", "S" + std::to_string(depth)},
                        {"vertices", n},
                        {"triangles", surface.triangle_count()},
                        {"setup_ms", setup_ms},
                        {"stencil_terms_per_vertex", double(surface.stencil_terms()) / double(n)},
                        {"factorised_terms_per_vertex", double(factorised.stencil_terms()) / double(n)},
                        {"refine_ns_per_vertex", per_v},
                        {"factorised_soa_ns_per_vertex", factorised_ns / double(n)},
                        {"far_update_values_ns_per_vertex", far_ns / double(n)},
                        {"forms_max_difference_m", form_gap},
                        {"normals_ns_per_vertex", normals_ns / double(n)},
                        {"walker_us", walker_ns / 1000.0},
                        {"walker_ns_per_vertex", walker_ns / double(n)}});
      routes.push_back({{"route", "skin cage + refine S" + std::to_string(depth)}, {"level", "S" + std::to_string(depth)},
                        {"vertices", n}, {"triangles", surface.triangle_count()},
                        {"walker_us", walker_ns / 1000.0}, {"ns_per_vertex", walker_ns / double(n)}});
      std::printf("%-6s %9zu %10zu %13.1f %11.2f   refine %.2f ns/v (factorised %.2f, Far UpdateValues %.2f), "
                  "normals %.2f ns/v, %.1f / %.1f terms per vertex, setup %.0f ms\n",
                  ("S" + std::to_string(depth)).c_str(), n, surface.triangle_count(), walker_ns / 1000.0,
                  walker_ns / double(n), per_v, factorised_ns / double(n), far_ns / double(n), normals_ns / double(n),
                  double(surface.stencil_terms()) / double(n), double(factorised.stencil_terms()) / double(n), setup_ms);
    }
    out["levels"] = levels;
    out["routes"] = routes;
    out["refine_target_ns_per_vertex"] = 30;

    // Deviation from the directly skinned level 0, at rest and flexed.
    nlohmann::json dev = nlohmann::json::array();
    const SkinLayout level0 = make_skin_layout(body.levels[0]);
    std::printf("deviation of level 0 from the refined cage (max / mean, mm):\n");
    for (const char* pose : {"rest", "flexed"}) {
      WalkerLanes l = scene.lanes();
      if (std::string(pose) == "rest") {
        for (std::uint32_t j = 0; j < l.joints; ++j)
          for (int c = 0; c < 4; ++c) l.local_rotation[(j * 4 + c) * l.stride] = c == 3 ? 1.0f : 0.0f;
        run_or_throw(make_fk_job(skeleton, scene.table(initial_slot(scene))), "fk");
      } else {
        flex(skeleton, l, scene.table(initial_slot(scene)));
      }
      const std::size_t s0 = pad_to_lanes(level0.vertex_count);
      std::vector<float> l0(6 * s0);
      run_or_throw(make_skin_walker_job(level0, scene.table(initial_slot(scene)), 0, skin_output_in(l0.data(), s0)), "skin");
      for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
        const std::shared_ptr<const SubdivSurface> surface = body_subdiv_surface(body, depth);
        const std::size_t st = pad_to_lanes(surface->vertex_count);
        std::vector<float> r(6 * st);
        run_or_throw(make_subdiv_walker_job(*surface, scene.table(initial_slot(scene)), 0, skin_output_in(r.data(), st)), "subdiv");
        const Deviation d = surface_deviation(l0, level0.vertex_count, s0, r, surface->vertex_count, st, surface->triangles);
        dev.push_back({{"pose", pose}, {"level", "S" + std::to_string(depth)}, {"max_deviation_m", d.max_m},
                       {"mean_deviation_m", d.mean_m}});
        std::printf("  %-7s S%d  %7.2f / %5.2f\n", pose, depth, 1000.0 * d.max_m, 1000.0 * d.mean_m);
        if (std::string(pose) == "flexed" && depth == 2) out["max_deviation_m"] = d.max_m;
      }
    }
    out["deviation"] = dev;
    out["deviation_definition"] =
        "for each vertex of the directly skinned level-0 mesh, the distance to the nearest point of the refined "
        "cage's triangles; flexed = left elbow and knee at 120 deg; max_deviation_m is flexed S2";
    out["refine_target_met"] = refine_ok;
    if (!o.json.empty()) write_json_file(o.json, out);
    std::printf("refine target (<= 30 ns per refined vertex, one core) %s\n", refine_ok ? "met" : "MISSED");
  } catch (const std::exception& e) {
    print_error("report subdiv", error_text(e));
    return 1;
  }
  return 0;
}

}  // namespace

void add_subdiv_report(CLI::App& report, int& exit_code) {
  auto o = std::make_shared<SubdivReportOptions>();
  auto* cmd = report.add_subcommand("subdiv", "Time the per-frame cage refinement (S1..S3) against skinning the mesh "
                                              "levels, and measure the refined surface's deviation from level 0");
  cmd->add_option("--json", o->json, "Write the report here");
  cmd->add_option("--batches", o->batches, "Timing batches per measurement (the best is kept)")->capture_default_str()
      ->check(whole_in(1, 1000));
  cmd->callback([o, &exit_code] { exit_code = run_subdiv_report(*o); });
}

}  // namespace strata::cli
