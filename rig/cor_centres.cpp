#include "rig/cor_centres.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/fnv_hasher.h"
#include "rig/body_cache.h"

namespace strata {
namespace {

// Bumped whenever the result for the same inputs would change (the similarity, the triangle weights, the
// fallback): the key then differs and stale files are ignored.
constexpr std::uint32_t kCorVersion = 1;
constexpr char kCentresMagic[8] = {'S', 'T', 'R', 'C', 'O', 'R', '0', '1'};
constexpr std::uint64_t kMaxCentres = 1u << 26;


// A sparse weight vector: joints ascending, weights > 0, summing to 1.
struct Sparse {
  std::array<std::int16_t, 12> joint{};
  std::array<double, 12> weight{};
  int count = 0;
  double of(std::int16_t j) const {
    for (int i = 0; i < count; ++i)
      if (joint[static_cast<std::size_t>(i)] == j) return weight[static_cast<std::size_t>(i)];
    return 0.0;
  }
};

Sparse vertex_weights(const SkinBinding& b, std::size_t v) {
  Sparse s;
  double total = 0.0;
  for (int k = 0; k < kMaxInfluences; ++k)
    if (b.weights[v][k] > 0.0f) total += b.weights[v][k];
  if (!(total > 0.0)) return s;
  std::array<std::pair<std::int16_t, double>, kMaxInfluences> pairs{};
  int n = 0;
  for (int k = 0; k < kMaxInfluences; ++k)
    if (b.weights[v][k] > 0.0f) pairs[static_cast<std::size_t>(n++)] = {b.joints[v][k], b.weights[v][k] / total};
  std::sort(pairs.begin(), pairs.begin() + n);
  for (int i = 0; i < n; ++i) {
    // The same joint twice in one binding row: merge, so the similarity counts it once.
    if (s.count > 0 && s.joint[static_cast<std::size_t>(s.count - 1)] == pairs[static_cast<std::size_t>(i)].first) {
      s.weight[static_cast<std::size_t>(s.count - 1)] += pairs[static_cast<std::size_t>(i)].second;
      continue;
    }
    s.joint[static_cast<std::size_t>(s.count)] = pairs[static_cast<std::size_t>(i)].first;
    s.weight[static_cast<std::size_t>(s.count)] = pairs[static_cast<std::size_t>(i)].second;
    ++s.count;
  }
  return s;
}

// Le & Hodgins' similarity over the joint pairs of the vertex (only those can contribute). The ordered sum over
// j != k counts each pair twice with the same term; the factor 2 cancels in the weighted mean, so each unordered
// pair is counted once.
double similarity(const Sparse& v, const Sparse& t, double inv_sigma2) {
  std::array<double, kMaxInfluences> tw{};
  for (int i = 0; i < v.count; ++i) tw[static_cast<std::size_t>(i)] = t.of(v.joint[static_cast<std::size_t>(i)]);
  double sum = 0.0;
  for (int a = 0; a < v.count; ++a)
    for (int b = a + 1; b < v.count; ++b) {
      const double pa = v.weight[static_cast<std::size_t>(a)], pb = v.weight[static_cast<std::size_t>(b)];
      const double ta = tw[static_cast<std::size_t>(a)], tb = tw[static_cast<std::size_t>(b)];
      if (ta == 0.0 || tb == 0.0) continue;
      const double d = pa * tb - pb * ta;
      sum += pa * pb * ta * tb * std::exp(-d * d * inv_sigma2);
    }
  return sum;
}

std::uint32_t pair_key(std::int16_t a, std::int16_t b) {
  return (static_cast<std::uint32_t>(static_cast<std::uint16_t>(a)) << 16) | static_cast<std::uint16_t>(b);
}

}  // namespace

CorCentres compute_cor_centres(const Mesh& mesh, const SkinBinding& binding, const CorOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = mesh.vertex_count();
  if (binding.vertex_count() != n)
    throw std::invalid_argument("compute_cor_centres: binding and mesh differ in vertex count");
  CorCentres out;
  out.centres = mesh.positions;
  std::vector<Sparse> vw(n);
  for (std::size_t v = 0; v < n; ++v) vw[v] = vertex_weights(binding, v);

  // Triangles: mean weights (the three vertices' sparse weights averaged), area, centroid.
  const std::size_t tris = mesh.triangles.size() / 3;
  std::vector<Sparse> tw(tris);
  std::vector<double> area(tris);
  std::vector<glm::dvec3> centroid(tris);
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> by_pair;
  for (std::size_t t = 0; t < tris; ++t) {
    const std::uint32_t i[3] = {mesh.triangles[3 * t], mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]};
    if (i[0] >= n || i[1] >= n || i[2] >= n) throw std::invalid_argument("compute_cor_centres: triangle index out of range");
    std::map<std::int16_t, double> sum;
    for (const std::uint32_t v : i)
      for (int k = 0; k < vw[v].count; ++k)
        sum[vw[v].joint[static_cast<std::size_t>(k)]] += vw[v].weight[static_cast<std::size_t>(k)] / 3.0;
    Sparse& s = tw[t];
    for (const auto& [j, w] : sum) {
      if (s.count == 12) break;
      s.joint[static_cast<std::size_t>(s.count)] = j;
      s.weight[static_cast<std::size_t>(s.count++)] = w;
    }
    const glm::dvec3 a(mesh.positions[i[0]]), b(mesh.positions[i[1]]), c(mesh.positions[i[2]]);
    area[t] = 0.5 * glm::length(glm::cross(b - a, c - a));
    centroid[t] = (a + b + c) / 3.0;
    if (!(area[t] > 0.0) || !std::isfinite(area[t])) continue;  // contributes nothing: not indexed
    for (int x = 0; x < s.count; ++x)
      for (int y = x + 1; y < s.count; ++y)
        by_pair[pair_key(s.joint[static_cast<std::size_t>(x)], s.joint[static_cast<std::size_t>(y)])].push_back(
            static_cast<std::uint32_t>(t));
  }

  // Influence sets of the vertices that need a centre, each with the triangles sharing one of its pairs.
  std::map<std::vector<std::int16_t>, std::vector<std::uint32_t>> sets;
  for (std::size_t v = 0; v < n; ++v)
    if (vw[v].count >= 2)
      sets[std::vector<std::int16_t>(vw[v].joint.begin(), vw[v].joint.begin() + vw[v].count)].push_back(
          static_cast<std::uint32_t>(v));
  const double inv_sigma2 = 1.0 / (options.sigma * options.sigma);
  std::vector<std::uint8_t> solved(n, 0);
  // Named references, not a structured binding: clang before 16 cannot capture a binding in the lambda below.
  for (const auto& set : sets) {
    const std::vector<std::int16_t>& joints = set.first;
    const std::vector<std::uint32_t>& vertices = set.second;
    std::vector<std::uint32_t> candidates;
    for (std::size_t a = 0; a < joints.size(); ++a)
      for (std::size_t b = a + 1; b < joints.size(); ++b) {
        const auto it = by_pair.find(pair_key(joints[a], joints[b]));
        if (it != by_pair.end()) candidates.insert(candidates.end(), it->second.begin(), it->second.end());
      }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    // Each vertex sums its candidates in ascending triangle order, whatever thread runs it: deterministic.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t k = r.begin(); k < r.end(); ++k) {
                          const std::uint32_t v = vertices[k];
                          glm::dvec3 num(0.0);
                          double den = 0.0;
                          for (const std::uint32_t t : candidates) {
                            const double s = similarity(vw[v], tw[t], inv_sigma2) * area[t];
                            num += s * centroid[t];
                            den += s;
                          }
                          if (den > 1e-300 && std::isfinite(den)) {
                            const glm::dvec3 c = num / den;
                            if (std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)) {
                              out.centres[v] = glm::vec3(c);
                              solved[v] = 1;
                            }
                          }
                        }
                      });
    for (const std::uint32_t v : vertices) (solved[v] ? out.solved : out.fallback) += 1;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

std::uint64_t cor_cache_key(const Mesh& mesh, const SkinBinding& binding, const CorOptions& options) {
  FnvHasher h;
  h.bytes(&kCorVersion, sizeof kCorVersion);
  h.bytes(&options.sigma, sizeof options.sigma);
  const std::uint64_t counts[3] = {mesh.positions.size(), mesh.triangles.size(), binding.vertex_count()};
  h.bytes(counts, sizeof counts);
  h.bytes(mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
  h.bytes(mesh.triangles.data(), mesh.triangles.size() * sizeof(std::uint32_t));
  h.bytes(binding.joints.data(), binding.joints.size() * sizeof(binding.joints[0]));
  h.bytes(binding.weights.data(), binding.weights.size() * sizeof(binding.weights[0]));
  return h.h;
}

std::optional<std::vector<glm::vec3>> load_cor_cache(const std::filesystem::path& file, std::uint64_t key) {
  const std::optional<std::vector<float>> f = load_float_cache(file, kCentresMagic, key, 3, kMaxCentres);
  if (!f) return std::nullopt;
  std::vector<glm::vec3> c(f->size() / 3);
  for (std::size_t i = 0; i < c.size(); ++i) c[i] = {(*f)[3 * i], (*f)[3 * i + 1], (*f)[3 * i + 2]};
  return c;
}

void save_cor_cache(const std::filesystem::path& file, std::uint64_t key, const std::vector<glm::vec3>& centres) {
  std::vector<float> f(3 * centres.size());
  for (std::size_t i = 0; i < centres.size(); ++i) f[3 * i] = centres[i].x, f[3 * i + 1] = centres[i].y, f[3 * i + 2] = centres[i].z;
  save_float_cache(file, kCentresMagic, key, 3, f);
}

CorCentres cached_cor_centres(const Mesh& mesh, const SkinBinding& binding, const CorOptions& options) {
  const std::uint64_t key = cor_cache_key(mesh, binding, options);
  const std::optional<std::filesystem::path> dir = body_cache_directory();
  // One file per key: a body's levels (and an edited binding beside the shipped one) coexist.
  char name[40];
  std::snprintf(name, sizeof name, "cor-%016llx.bin", static_cast<unsigned long long>(key));
  if (dir) {
    if (auto c = load_cor_cache(*dir / name, key); c && c->size() == mesh.vertex_count()) {
      CorCentres out;
      out.centres = std::move(*c);
      out.from_cache = true;
      for (std::size_t v = 0; v < binding.vertex_count(); ++v)
        if (binding.influence_count(v) >= 2)
          (out.centres[v] == mesh.positions[v] ? out.fallback : out.solved) += 1;
      return out;
    }
  }
  CorCentres out = compute_cor_centres(mesh, binding, options);
  if (dir) save_cor_cache(*dir / name, key, out.centres);
  return out;
}

std::shared_ptr<const CorCentres> body_cor_centres(const Body& body, int level) {
  const BodyLevel* l = body_level_or_cage(body, level);
  if (!l) return nullptr;
  return body.cor.get(per_level_slot(level), [&] { return std::make_shared<const CorCentres>(cached_cor_centres(l->mesh, l->binding)); });
}

}  // namespace strata
