#include "rig/subdiv_topology.h"

#include "rig/cor_centres.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include "rig/subdiv_refiner.h"

namespace strata {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

namespace {

// The cage's texture coordinates as one face-varying channel: values and an index per triangle corner. Per-vertex
// UVs index like the triangles; per-corner ones as their distinct values per vertex (corner_uv_values: a seam
// gives a vertex two). Empty when the cage has neither.
struct UvChannel {
  std::vector<glm::vec2> values;
  std::vector<Far::Index> indices;
};
UvChannel uv_channel_of(const Mesh& cage) {
  UvChannel c;
  if (cage.corner_uvs.size() == cage.triangles.size() && !cage.triangles.empty()) {
    CornerUvValues split = corner_uv_values(cage);
    c.values = std::move(split.uvs);
    c.indices.assign(split.of_corner.begin(), split.of_corner.end());
  } else if (cage.uvs.size() == cage.vertex_count() && cage.vertex_count() > 0) {
    c.values = cage.uvs;
    c.indices.assign(cage.triangles.begin(), cage.triangles.end());
  }
  return c;
}

}  // namespace

std::unique_ptr<Far::TopologyRefiner> make_cage_refiner(const Mesh& cage) {
  if (cage.vertex_count() == 0 || cage.triangle_count() == 0)
    throw std::invalid_argument("subdivision cage '" + cage.name + "' is empty");
  const auto faces = static_cast<int>(cage.triangle_count());
  std::vector<int> verts_per_face(static_cast<std::size_t>(faces), 3);
  std::vector<Far::Index> indices(cage.triangles.begin(), cage.triangles.end());
  Far::TopologyDescriptor desc;
  desc.numVertices = static_cast<int>(cage.vertex_count());
  desc.numFaces = faces;
  desc.numVertsPerFace = verts_per_face.data();
  desc.vertIndicesPerFace = indices.data();
  // Texture coordinates become one face-varying channel (uv_channel_of), so the refined ones keep the cage's
  // seams.
  const UvChannel uvs = uv_channel_of(cage);
  Far::TopologyDescriptor::FVarChannel uv_channel;
  if (!uvs.values.empty()) {
    uv_channel.numValues = static_cast<int>(uvs.values.size());
    uv_channel.valueIndices = uvs.indices.data();
    desc.numFVarChannels = 1;
    desc.fvarChannels = &uv_channel;
  }
  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  sdc.SetFVarLinearInterpolation(Sdc::Options::FVAR_LINEAR_CORNERS_ONLY);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(Factory::Create(desc, Factory::Options(Sdc::SCHEME_LOOP, sdc)));
  if (!refiner) throw std::invalid_argument("OpenSubdiv rejected the topology of cage '" + cage.name + "'");
  return refiner;
}

namespace {

// PrimvarRefiner::Interpolate calls dst[i].Clear() and dst[i].AddWithWeight(src[j], w) for every term of every
// refined vertex. Feeding it vertex ids instead of positions records the refinement matrix itself, one level at
// a time, without depending on how a stencil table orders or factorises its entries.
struct SourceVertex {
  std::uint32_t index;
};
struct RecordedRow {
  std::vector<std::pair<std::uint32_t, float>> terms;
  void Clear() { terms.clear(); }
  void AddWithWeight(const SourceVertex& v, float w) { terms.emplace_back(v.index, w); }
  // A refined vertex built from another refined vertex of the same level (Catmull-Clark's face points; the
  // template instantiates it for Loop too): compose, i.e. append that row's terms scaled.
  void AddWithWeight(const RecordedRow& row, float w) {
    for (const auto& [index, weight] : row.terms) terms.emplace_back(index, w * weight);
  }
};

// Rows to CSR; terms of one source vertex are merged (sorted by source, so a row also reads memory forwards).
SubdivStencils to_stencils(std::vector<RecordedRow>& rows, std::uint32_t source_count) {
  SubdivStencils s;
  s.source_count = source_count;
  s.offsets.reserve(rows.size() + 1);
  s.offsets.push_back(0);
  for (RecordedRow& row : rows) {
    std::sort(row.terms.begin(), row.terms.end());
    for (std::size_t k = 0; k < row.terms.size(); ++k) {
      if (k > 0 && row.terms[k].first == row.terms[k - 1].first) {
        s.weights.back() += row.terms[k].second;
        continue;
      }
      s.indices.push_back(row.terms[k].first);
      s.weights.push_back(row.terms[k].second);
    }
    s.offsets.push_back(static_cast<std::uint32_t>(s.indices.size()));
  }
  return s;
}

std::vector<SubdivStencils> level_by_level(const Far::TopologyRefiner& refiner, int depth) {
  std::vector<SubdivStencils> steps;
  const Far::PrimvarRefiner primvar(refiner);
  for (int level = 1; level <= depth; ++level) {
    const int sources = refiner.GetLevel(level - 1).GetNumVertices();
    std::vector<SourceVertex> src(static_cast<std::size_t>(sources));
    for (int i = 0; i < sources; ++i) src[static_cast<std::size_t>(i)].index = static_cast<std::uint32_t>(i);
    std::vector<RecordedRow> dst(static_cast<std::size_t>(refiner.GetLevel(level).GetNumVertices()));
    primvar.Interpolate(level, src, dst);
    steps.push_back(to_stencils(dst, static_cast<std::uint32_t>(sources)));
  }
  return steps;
}

SubdivStencils factorised(const Far::TopologyRefiner& refiner) {
  Far::StencilTableFactoryReal<float>::Options options;
  options.generateIntermediateLevels = false;  // only the last level, indexed like GetLevel(L)'s vertices
  options.generateOffsets = true;
  options.interpolationMode = Far::StencilTableFactoryReal<float>::INTERPOLATE_VERTEX;
  std::unique_ptr<const Far::StencilTableReal<float>> table(Far::StencilTableFactoryReal<float>::Create(refiner, options));
  std::vector<RecordedRow> rows(static_cast<std::size_t>(table->GetNumStencils()));
  for (int i = 0; i < table->GetNumStencils(); ++i) {
    const Far::Stencil stencil = table->GetStencil(static_cast<Far::Index>(i));
    for (int k = 0; k < stencil.GetSize(); ++k)
      rows[static_cast<std::size_t>(i)].terms.emplace_back(static_cast<std::uint32_t>(stencil.GetVertexIndices()[k]),
                                                           stencil.GetWeights()[k]);
  }
  return to_stencils(rows, static_cast<std::uint32_t>(refiner.GetLevel(0).GetNumVertices()));
}

// New number of each vertex of a refined level: the order in which its faces first use it. OpenSubdiv numbers a
// level's vertices by kind (children of vertices, then of edges), so a face's three corners land far apart in
// memory; first-use order follows the faces, which themselves follow the (vertex-cache ordered) cage's faces.
std::vector<std::uint32_t> first_use_order(const Far::TopologyLevel& level) {
  std::vector<std::uint32_t> order(static_cast<std::size_t>(level.GetNumVertices()), UINT32_MAX);
  std::uint32_t next = 0;
  for (int f = 0; f < level.GetNumFaces(); ++f)
    for (const Far::Index v : level.GetFaceVertices(f))
      if (order[static_cast<std::size_t>(v)] == UINT32_MAX) order[static_cast<std::size_t>(v)] = next++;
  for (std::uint32_t& o : order)
    if (o == UINT32_MAX) o = next++;  // a vertex no face uses (not produced by Loop refinement; kept anyway)
  return order;
}

// Moves row r of `s` to position new_of_old[r].
void renumber_rows(SubdivStencils& s, const std::vector<std::uint32_t>& new_of_old) {
  std::vector<std::uint32_t> old_of_new(new_of_old.size());
  for (std::uint32_t r = 0; r < new_of_old.size(); ++r) old_of_new[new_of_old[r]] = r;
  SubdivStencils out;
  out.source_count = s.source_count;
  out.offsets.push_back(0);
  for (const std::uint32_t r : old_of_new) {
    for (std::uint32_t k = s.offsets[r]; k < s.offsets[r + 1]; ++k) {
      out.indices.push_back(s.indices[k]);
      out.weights.push_back(s.weights[k]);
    }
    out.offsets.push_back(static_cast<std::uint32_t>(out.indices.size()));
  }
  s = std::move(out);
}

}  // namespace

SubdivSurface make_subdiv_surface(const BodyLevel& cage, int depth, StencilForm form) {
  if (depth < 1 || depth > kMaxSubdivDepth)
    throw std::invalid_argument("subdivision level must be 1..3, got " + std::to_string(depth));
  if (cage.binding.vertex_count() != cage.mesh.vertex_count())
    throw std::invalid_argument("cage '" + cage.mesh.name + "': binding has " +
                                std::to_string(cage.binding.vertex_count()) + " vertices, mesh " +
                                std::to_string(cage.mesh.vertex_count()));
  std::unique_ptr<Far::TopologyRefiner> refiner = make_cage_refiner(cage.mesh);
  // Only the last level's faces are drawn; intermediate levels need no full topology.
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(depth));

  SubdivSurface s;
  s.depth = depth;
  s.cage_layout = make_skin_layout(cage);
  // The cage is a few hundred vertices: its centres of rotation cost milliseconds, so every surface carries them
  // and a crowd can switch to SkinningMode::CentresOfRotation at S levels without rebuilding shared data.
  set_cor_centres(s.cage_layout, compute_cor_centres(cage.mesh, cage.binding).centres);
  s.steps = form == StencilForm::LevelByLevel ? level_by_level(*refiner, depth)
                                              : std::vector<SubdivStencils>{factorised(*refiner)};
  // The skinning kernel writes the cage in layout order: point the first step's sources there once, so the frame
  // needs no reordering pass.
  std::vector<std::uint32_t> rank(s.cage_layout.original.size());
  for (std::uint32_t i = 0; i < rank.size(); ++i) rank[s.cage_layout.original[i]] = i;
  for (std::uint32_t& index : s.steps.front().indices) index = rank[index];

  // Renumber every refined level's vertices in first-use order (the step making it and the one reading it
  // agree); measured at S2 on one core: 24 -> 17 ns per refined vertex for the whole walker.
  std::vector<std::uint32_t> last_order;
  for (int level = 1; level <= depth; ++level) {
    if (form == StencilForm::Factorised && level < depth) continue;
    const std::vector<std::uint32_t> order = first_use_order(refiner->GetLevel(level));
    const std::size_t step = form == StencilForm::Factorised ? 0 : static_cast<std::size_t>(level - 1);
    renumber_rows(s.steps[step], order);
    if (step + 1 < s.steps.size())
      for (std::uint32_t& index : s.steps[step + 1].indices) index = order[index];
    if (level == depth) last_order = order;
  }
  s.opensubdiv_vertex.resize(last_order.size());
  for (std::uint32_t v = 0; v < last_order.size(); ++v) s.opensubdiv_vertex[last_order[v]] = v;

  const Far::TopologyLevel& last = refiner->GetLevel(depth);
  s.vertex_count = static_cast<std::uint32_t>(last.GetNumVertices());
  s.triangles.reserve(static_cast<std::size_t>(last.GetNumFaces()) * 3);
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    const Far::ConstIndexArray v = last.GetFaceVertices(f);
    if (v.size() != 3) throw std::logic_error("Loop refinement produced a face with " + std::to_string(v.size()) + " vertices");
    for (int k = 0; k < 3; ++k) s.triangles.push_back(last_order[static_cast<std::size_t>(v[k])]);
  }

  if (refiner->GetNumFVarChannels() > 0) {
    // UVs are refined once, level by level, as face-varying data.
    struct Uv {
      glm::vec2 value{0.0f};
      void Clear() { value = glm::vec2(0.0f); }
      void AddWithWeight(const Uv& src, float w) { value += w * src.value; }
    };
    const UvChannel channel = uv_channel_of(cage.mesh);  // the values make_cage_refiner indexed
    std::vector<Uv> uv(channel.values.size());
    for (std::size_t i = 0; i < uv.size(); ++i) uv[i].value = channel.values[i];
    const Far::PrimvarRefiner primvar(*refiner);
    for (int level = 1; level <= depth; ++level) {
      std::vector<Uv> next(static_cast<std::size_t>(refiner->GetLevel(level).GetNumFVarValues(0)));
      primvar.InterpolateFaceVarying(level, uv, next, 0);
      uv = std::move(next);
    }
    s.uvs.reserve(uv.size());
    for (const Uv& u : uv) s.uvs.push_back(u.value);
    s.uv_triangles.reserve(s.triangles.size());
    for (int f = 0; f < last.GetNumFaces(); ++f) {
      const Far::ConstIndexArray v = last.GetFaceFVarValues(f, 0);
      for (int k = 0; k < 3; ++k) s.uv_triangles.push_back(static_cast<std::uint32_t>(v[k]));
    }
  }
  return s;
}

std::shared_ptr<const SubdivSurface> body_subdiv_surface(const Body& body, int depth) {
  if (!body.cage) return nullptr;
  return body.subdiv.get(depth, [&] { return std::make_shared<const SubdivSurface>(make_subdiv_surface(*body.cage, depth)); });
}

}  // namespace strata
