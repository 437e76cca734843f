// Google Benchmark: the analytic limb IK, per solve and as a system over a crowd of the shipped skeleton.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "io/hanim_loader.h"
#include "reference/fk_reference.h"
#include "components/walker.h"
#include "systems/ik.h"

namespace {

// Walking-range goals for one limb: hip/shoulder swing +-20 deg and knee/elbow bend 3..45 deg, as the shipped
// walk clip does; the goal is the lower joint's FK position. The pole swivel is feasible for all of them.
std::vector<strata::LimbSolveInput> walking_goals(const strata::Skeleton& s, const strata::LimbChain& limb,
                                                  bool leg, float swivel_offset) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<float> swing(-0.35f, 0.35f), bend(0.05f, 0.8f);
  std::vector<strata::LimbSolveInput> goals;
  for (int i = 0; i < 1024; ++i) {
    std::vector<glm::quat> r(s.joint_count(), glm::quat(1, 0, 0, 0));
    r[limb.upper] = glm::angleAxis(swing(rng), glm::vec3(1, 0, 0));
    r[limb.middle] = glm::angleAxis(leg ? bend(rng) : -bend(rng), glm::vec3(1, 0, 0));
    const strata::ReferencePose ref = strata::fk_reference(s, r, glm::vec3(0.0f));
    strata::LimbSolveInput in;
    in.goal = glm::vec3(ref.world[limb.lower][3]);
    in.pole = limb.pole;
    in.swivel_offset = swivel_offset;
    goals.push_back(in);
  }
  return goals;
}

void run_solves(benchmark::State& state, float swivel_offset) {
  const strata::Skeleton s = strata::load_default_humanoid().skeleton;
  const std::vector<strata::LimbChain> limbs = strata::make_limbs(s);
  const bool leg = state.range(0) == 0;
  const strata::LimbChain& limb = limbs[leg ? strata::kLeftLeg : strata::kLeftArm];
  const std::vector<strata::LimbSolveInput> goals = walking_goals(s, limb, leg, swivel_offset);
  std::size_t i = 0, moved = 0, solves = 0;
  for (auto _ : state) {
    const strata::LimbSolveResult r = strata::solve_limb(s, limb, goals[i]);
    benchmark::DoNotOptimize(r);
    moved += (r.flags & strata::kIkSwivelMoved) != 0;
    ++solves;
    i = (i + 1) % goals.size();
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(leg ? "l_leg" : "l_arm");
  state.counters["moved_fraction"] = solves ? static_cast<double>(moved) / static_cast<double>(solves) : 0.0;
}

// Typical walking goals: the requested (pole) swivel is feasible, the fast path.
void BM_SolveLimbWalking(benchmark::State& state) { run_solves(state, 0.0f); }
BENCHMARK(BM_SolveLimbWalking)->Arg(0)->Arg(1)->Unit(benchmark::kNanosecond);

// The same goals asking for a knee pointing backwards / elbow forwards: infeasible, so the swivel search runs.
void BM_SolveLimbSwivelSearch(benchmark::State& state) { run_solves(state, 2.8f); }
BENCHMARK(BM_SolveLimbSwivelSearch)->Arg(0)->Arg(1)->Unit(benchmark::kNanosecond);

// The system on one thread: walkers in walking-range poses (hips and shoulders swinging, knees and elbows bent,
// pelvis and spine turned a little, root bobbing), each limb asked to reach the pose FK gave it: legs with
// position + orientation goals, as stance feet are, arms with position goals. Built on a bare walker table so the
// number measures IK alone.
void BM_IkSystemSingleThread(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const strata::Skeleton s = strata::load_default_humanoid().skeleton;
  const std::vector<strata::LimbChain> limbs = strata::make_limbs(s);
  const auto joints = static_cast<std::uint32_t>(s.joint_count());
  auto table = strata::make_walker_table("bench", joints);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> swing(-0.35f, 0.35f), bend(0.05f, 0.8f), turn(-0.1f, 0.1f);
  const auto walkers = static_cast<std::size_t>(state.range(0));
  for (std::size_t w = 0; w < walkers; ++w) {
    const std::uint32_t block = table->add(strata::Entity{static_cast<std::uint32_t>(w + 1), 1});
    std::vector<glm::quat> pose(joints, glm::quat(1, 0, 0, 0));
    pose[0] = glm::angleAxis(turn(rng) * 10.0f, glm::vec3(0, 1, 0));  // heading
    for (const char* spine : {"sacroiliac", "vl5", "vt6"})
      pose[s.find_joint(spine)] =
          glm::angleAxis(turn(rng), glm::vec3(0, 1, 0)) * glm::angleAxis(turn(rng), glm::vec3(1, 0, 0));
    for (const strata::LimbChain& limb : limbs) {
      const bool leg = limb.flexion_axis.x > 0.0f;
      pose[limb.upper] = glm::angleAxis(swing(rng), glm::vec3(1, 0, 0));
      pose[limb.middle] = glm::angleAxis(leg ? bend(rng) : -bend(rng), glm::vec3(1, 0, 0));
    }
    const glm::vec3 root(0.0f, -0.02f * static_cast<float>(w % 3), 0.0f);
    const strata::ReferencePose ref = strata::fk_reference(s, pose, root);
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      auto goal = [&](std::uint32_t c) -> float& {
        return table->f32(strata::kWalkerIkGoal, static_cast<std::uint32_t>(k * strata::kIkGoalFloats + c))[block];
      };
      const glm::vec3 g(ref.world[limbs[k].lower][3]);
      const glm::quat q = glm::quat_cast(glm::mat3(ref.world[limbs[k].lower]));
      goal(strata::kGoalPx) = g.x, goal(strata::kGoalPy) = g.y, goal(strata::kGoalPz) = g.z;
      goal(strata::kGoalQx) = q.x, goal(strata::kGoalQy) = q.y;
      goal(strata::kGoalQz) = q.z, goal(strata::kGoalQw) = q.w;
      table->i32(strata::kWalkerIkMode, static_cast<std::uint32_t>(k))[block] =
          static_cast<std::int32_t>(k < 2 ? strata::IkMode::PositionOrientation : strata::IkMode::Position);
    }
    for (std::uint32_t j = 0; j < joints; ++j) {
      const float comp[4] = {pose[j].x, pose[j].y, pose[j].z, pose[j].w};
      for (std::uint32_t c = 0; c < 4; ++c) table->f32(strata::kWalkerLocalRotation, j * 4 + c)[block] = comp[c];
    }
    for (std::uint32_t c = 0; c < 3; ++c) table->f32(strata::kWalkerRootTranslation, c)[block] = root[c];
  }
  const strata::WalkerLanes lanes = strata::walker_lanes(*table, joints);
  const strata::IkJob job = strata::make_ik_job(s, limbs, *table);
  for (auto _ : state) {
    if (!job.run()) state.SkipWithError("invalid IkJob");
    benchmark::ClobberMemory();
  }
  std::size_t reached = 0, moved = 0;
  for (std::size_t w = 0; w < lanes.count; ++w)
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      const std::uint32_t flags = lanes.ik_flags[k * lanes.stride + w];
      reached += (flags & strata::kIkReached) != 0;
      moved += (flags & strata::kIkSwivelMoved) != 0;
    }
  const double solves = static_cast<double>(lanes.count * limbs.size());
  state.SetItemsProcessed(state.iterations() * static_cast<long>(lanes.count * limbs.size()));
  state.counters["walkers"] = static_cast<double>(lanes.count);
  state.counters["reached_fraction"] = static_cast<double>(reached) / solves;
  state.counters["moved_fraction"] = static_cast<double>(moved) / solves;
}
BENCHMARK(BM_IkSystemSingleThread)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
