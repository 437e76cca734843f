#include "io/gltf_export.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

// Debian's tinygltf is a shared library: the header alone declares the API (defining TINYGLTF_IMPLEMENTATION
// would compile a second copy of it into ours). Its writer is used rather than hand-written GLB chunks: it already
// lays out the JSON and BIN chunks with the padding the format requires, and the model it serialises is the same
// one io/gltf.cpp reads, so reader and writer cannot disagree on field names.
#include <tiny_gltf.h>

namespace strata {
namespace {

constexpr int kArrayBuffer = 34962;         // bufferView target of vertex attributes
constexpr int kElementArrayBuffer = 34963;  // bufferView target of indices

class GlbBuilder {
 public:
  explicit GlbBuilder(std::string path) : path_(std::move(path)) {
    model_.asset.version = "2.0";
    model_.asset.generator = "Strata (strata export)";
    model_.buffers.emplace_back();
  }

  [[noreturn]] void fail(const std::string& reason) const { throw ExportError(path_ + ": " + reason); }

  tinygltf::Model& model() { return model_; }

  // Appends raw bytes as one buffer view, 4-byte aligned (every component type used here is at most 4 bytes, so
  // each accessor starts on its component size, which glTF requires).
  int add_view(const void* data, std::size_t bytes, int target) {
    std::vector<unsigned char>& buffer = model_.buffers[0].data;
    buffer.resize((buffer.size() + 3) & ~std::size_t{3}, 0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), p, p + bytes);
    model_.bufferViews.push_back(view);
    return static_cast<int>(model_.bufferViews.size() - 1);
  }

  // A tightly packed accessor over `values` (count * components elements). Float accessors get min/max when
  // `bounds` is set (required for POSITION and animation input, optional elsewhere).
  template <typename T>
  int add_accessor(const std::vector<T>& values, int component_type, int type, int components, int target,
                   bool bounds) {
    const std::size_t count = values.size() / static_cast<std::size_t>(components);
    tinygltf::Accessor a;
    a.bufferView = add_view(values.data(), values.size() * sizeof(T), target);
    a.byteOffset = 0;
    a.componentType = component_type;
    a.type = type;
    a.count = count;
    if (bounds) {
      a.minValues.assign(components, std::numeric_limits<double>::infinity());
      a.maxValues.assign(components, -std::numeric_limits<double>::infinity());
      for (std::size_t i = 0; i < count; ++i)
        for (int c = 0; c < components; ++c) {
          const double v = static_cast<double>(values[i * components + c]);
          a.minValues[c] = std::min(a.minValues[c], v);
          a.maxValues[c] = std::max(a.maxValues[c], v);
        }
    }
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size() - 1);
  }

 private:
  std::string path_;
  tinygltf::Model model_;
};

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Up to four (joint, weight) pairs with weight > 0, duplicates merged, normalised so the float row sums to 1 as
// closely as float allows (the largest weight absorbs the rounding), unused slots (0, 0).
void skin_row(const SkinBinding& binding, std::size_t v, std::size_t joints, const GlbBuilder& out,
              std::array<std::uint16_t, 4>& js, std::array<float, 4>& ws) {
  js.fill(0);
  ws.fill(0.0f);
  int used = 0;
  for (int k = 0; k < kMaxInfluences; ++k) {
    const float w = binding.weights[v][k];
    if (!std::isfinite(w) || w < 0.0f)
      out.fail("vertex " + std::to_string(v) + ": weight " + std::to_string(k) + " is negative or not finite");
    if (w == 0.0f) continue;
    const int j = binding.joints[v][k];
    if (j < 0 || static_cast<std::size_t>(j) >= joints)
      out.fail("vertex " + std::to_string(v) + ": joint " + std::to_string(j) + " of a " + std::to_string(joints) +
               "-joint skeleton");
    int slot = 0;
    while (slot < used && js[slot] != j) ++slot;  // glTF forbids a joint twice in one row (the validator's error)
    if (slot == used) js[used++] = static_cast<std::uint16_t>(j);
    ws[slot] += w;
  }
  if (used == 0) out.fail("vertex " + std::to_string(v) + " has no skin weight");
  float sum = 0.0f;
  for (int k = 0; k < used; ++k) sum += ws[k];
  int largest = 0;
  for (int k = 0; k < used; ++k) {
    ws[k] /= sum;
    if (ws[k] > ws[largest]) largest = k;
  }
  float others = 0.0f;
  for (int k = 0; k < used; ++k)
    if (k != largest) others += ws[k];
  ws[largest] = 1.0f - others;
}

void check_times(const std::vector<float>& times, std::size_t values, const std::string& what, const GlbBuilder& out) {
  if (times.size() != values) out.fail(what + ": " + std::to_string(times.size()) + " times for " +
                                       std::to_string(values) + " values");
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (!std::isfinite(times[k]) || times[k] < 0.0f) out.fail(what + ": key " + std::to_string(k) + " time is negative or not finite");
    if (k > 0 && !(times[k] > times[k - 1]))
      out.fail(what + ": key times are not strictly increasing at key " + std::to_string(k));
  }
}

class TempFile {
 public:
  explicit TempFile(std::filesystem::path path) : path_(std::move(path)) {}
  ~TempFile() {
    if (!committed_) {
      std::error_code ec;
      std::filesystem::remove(path_, ec);
    }
  }
  const std::filesystem::path& path() const { return path_; }
  void commit() { committed_ = true; }

 private:
  std::filesystem::path path_;
  bool committed_ = false;
};

}  // namespace

GltfExportStats write_gltf_binary(const std::filesystem::path& path, const Skeleton& skeleton, const BodyLevel& level,
                                  const AnimationClip* clip, const std::string& name) {
  GlbBuilder out(path.string());
  if (path.empty() || !path.has_filename()) out.fail("not a file name");
  if (std::filesystem::is_directory(path)) out.fail("is a directory");
  tinygltf::Model& model = out.model();
  const std::size_t joints = skeleton.joint_count();
  const Mesh& mesh = level.mesh;
  const std::size_t vertices = mesh.vertex_count();
  if (joints == 0) out.fail("the skeleton has no joints");
  if (joints > 65535) out.fail("more than 65,535 joints do not fit JOINTS_0 as unsigned short");
  if (vertices == 0 || mesh.triangles.empty()) out.fail("the mesh is empty");
  if (level.binding.vertex_count() != vertices || level.binding.weights.size() != vertices)
    out.fail("the binding has " + std::to_string(level.binding.vertex_count()) + " vertices, the mesh " +
             std::to_string(vertices));
  if (skeleton.parents.size() != joints || skeleton.centers.size() != joints)
    out.fail("the skeleton's parent and centre lists do not match its joints");

  // --- joints --------------------------------------------------------------------------------------------------
  model.nodes.resize(joints);
  std::vector<int> roots;
  for (std::size_t j = 0; j < joints; ++j) {
    tinygltf::Node& node = model.nodes[j];
    node.name = skeleton.joint_names[j];
    const int parent = skeleton.parents[j];
    const glm::vec3 c = skeleton.centers[j];
    if (!finite(c)) out.fail("joint " + node.name + ": centre is not finite");
    if (parent >= static_cast<int>(j)) out.fail("joint " + node.name + ": parent does not come first");
    const glm::vec3 t = parent < 0 ? c : c - skeleton.centers[parent];
    node.translation = {t.x, t.y, t.z};
    if (parent < 0)
      roots.push_back(static_cast<int>(j));
    else
      model.nodes[parent].children.push_back(static_cast<int>(j));
  }
  std::vector<float> inverse_bind(16 * joints, 0.0f);
  for (std::size_t j = 0; j < joints; ++j) {
    float* m = &inverse_bind[16 * j];  // column-major translate(-c_j)
    m[0] = m[5] = m[10] = m[15] = 1.0f;
    m[12] = -skeleton.centers[j].x, m[13] = -skeleton.centers[j].y, m[14] = -skeleton.centers[j].z;
  }
  tinygltf::Skin skin;
  skin.name = name + "_skin";
  for (std::size_t j = 0; j < joints; ++j) skin.joints.push_back(static_cast<int>(j));
  skin.inverseBindMatrices =
      out.add_accessor(inverse_bind, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_MAT4, 16, 0, false);
  if (roots.size() == 1) skin.skeleton = roots[0];
  model.skins.push_back(skin);

  // --- mesh ----------------------------------------------------------------------------------------------------
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    if (mesh.triangles[i] >= vertices)
      out.fail("triangle " + std::to_string(i / 3) + ": index " + std::to_string(mesh.triangles[i]) + " of " +
               std::to_string(vertices) + " vertices");
  if (mesh.triangles.size() % 3) out.fail("the index count is not a multiple of 3");
  // Texture coordinates: per vertex as they are, or per corner (face-varying), where glTF's per-vertex attributes
  // need a vertex split at every UV seam: one written vertex per distinct (vertex, uv) pair, in first-use order.
  const bool corner_uvs = mesh.corner_uvs.size() == mesh.triangles.size();
  const bool vertex_uvs = !corner_uvs && mesh.uvs.size() == vertices;
  std::vector<std::uint32_t> written_of(vertices);  // the source vertex of each written vertex
  std::vector<glm::vec2> written_uv;
  std::vector<std::uint32_t> indices(mesh.triangles.begin(), mesh.triangles.end());
  if (corner_uvs) {
    for (std::size_t c = 0; c < mesh.corner_uvs.size(); ++c)
      if (!std::isfinite(mesh.corner_uvs[c].x) || !std::isfinite(mesh.corner_uvs[c].y))
        out.fail("triangle " + std::to_string(c / 3) + ": texture coordinate is not finite");
    CornerUvValues split = corner_uv_values(mesh);
    written_of = std::move(split.vertex);
    written_uv = std::move(split.uvs);
    indices = std::move(split.of_corner);
  } else {
    for (std::size_t v = 0; v < vertices; ++v) written_of[v] = static_cast<std::uint32_t>(v);
    if (vertex_uvs) written_uv = mesh.uvs;
  }
  const std::size_t written = written_of.size();
  std::vector<float> positions(3 * written), normals(3 * written), weights(4 * written), uvs;
  std::vector<std::uint16_t> joint_indices(4 * written);
  Mesh with_normals;
  const std::vector<glm::vec3>* source_normals = &mesh.normals;
  if (mesh.normals.size() != vertices) {
    with_normals = mesh;
    compute_normals(with_normals);
    source_normals = &with_normals.normals;
  }
  for (std::size_t w = 0; w < written; ++w) {
    const std::size_t v = written_of[w];
    const glm::vec3 p = mesh.positions[v];
    if (!finite(p)) out.fail("vertex " + std::to_string(v) + ": position is not finite");
    glm::vec3 n = (*source_normals)[v];
    const float len = glm::length(n);
    n = std::isfinite(len) && len > 1e-12f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);  // glTF normals are unit
    for (int c = 0; c < 3; ++c) positions[3 * w + c] = p[c], normals[3 * w + c] = n[c];
    std::array<std::uint16_t, 4> js;
    std::array<float, 4> ws;
    skin_row(level.binding, v, joints, out, js, ws);
    for (int c = 0; c < 4; ++c) joint_indices[4 * w + c] = js[c], weights[4 * w + c] = ws[c];
  }
  if (!written_uv.empty()) {
    // glTF's texture space has v down from the top-left corner; OBJ's (and Mesh's) v goes up from the bottom.
    uvs.reserve(2 * written);
    for (const glm::vec2& uv : written_uv) uvs.push_back(uv.x), uvs.push_back(1.0f - uv.y);
  }

  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.attributes["POSITION"] =
      out.add_accessor(positions, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3, kArrayBuffer, true);
  prim.attributes["NORMAL"] =
      out.add_accessor(normals, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3, kArrayBuffer, false);
  prim.attributes["JOINTS_0"] = out.add_accessor(joint_indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                                 TINYGLTF_TYPE_VEC4, 4, kArrayBuffer, false);
  prim.attributes["WEIGHTS_0"] =
      out.add_accessor(weights, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, 4, kArrayBuffer, false);
  if (!uvs.empty())
    prim.attributes["TEXCOORD_0"] =
        out.add_accessor(uvs, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, 2, kArrayBuffer, false);
  // 65,535 is the primitive-restart value of unsigned short indices and may not be used as an index.
  if (written < 65535) {
    const std::vector<std::uint16_t> idx(indices.begin(), indices.end());
    prim.indices = out.add_accessor(idx, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, 1,
                                    kElementArrayBuffer, false);
  } else {
    prim.indices = out.add_accessor(indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, 1,
                                    kElementArrayBuffer, false);
  }
  tinygltf::Material material;
  material.name = "skin";
  // A matte skin tone; glTF's default material is fully metallic, which renders a body almost black.
  material.pbrMetallicRoughness.baseColorFactor = {0.80, 0.60, 0.50, 1.0};
  material.pbrMetallicRoughness.metallicFactor = 0.0;
  material.pbrMetallicRoughness.roughnessFactor = 0.7;
  model.materials.push_back(material);
  prim.material = 0;
  tinygltf::Mesh gmesh;
  gmesh.name = mesh.name.empty() ? name : mesh.name;
  gmesh.primitives.push_back(prim);
  model.meshes.push_back(gmesh);

  tinygltf::Node body;
  body.name = name;
  body.mesh = 0;
  body.skin = 0;
  model.nodes.push_back(body);

  tinygltf::Scene scene;
  scene.name = name;
  scene.nodes = roots;
  scene.nodes.push_back(static_cast<int>(model.nodes.size() - 1));
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  // --- animation -----------------------------------------------------------------------------------------------
  std::size_t keys = 0;
  if (clip) {
    tinygltf::Animation anim;
    anim.name = clip->name.empty() ? "animation" : clip->name;
    // Tracks sampled at the same times (a baked clip's are all alike) share one input accessor.
    const std::vector<float>* last_times = nullptr;
    int last_input = -1;
    auto input_of = [&](const std::vector<float>& times) {
      if (!last_times || *last_times != times) {
        last_input = out.add_accessor(times, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, 1, 0, true);
        last_times = &times;
      }
      keys = std::max(keys, times.size());
      return last_input;
    };
    auto add_channel = [&](int input, int output, int node, const char* target) {
      tinygltf::AnimationSampler sampler;
      sampler.input = input;
      sampler.output = output;
      sampler.interpolation = "LINEAR";
      anim.samplers.push_back(sampler);
      tinygltf::AnimationChannel channel;
      channel.sampler = static_cast<int>(anim.samplers.size() - 1);
      channel.target_node = node;
      channel.target_path = target;
      anim.channels.push_back(channel);
    };
    auto check_joint = [&](std::int32_t joint, const std::string& what) {
      if (joint < 0 || static_cast<std::size_t>(joint) >= joints)
        out.fail(what + ": joint " + std::to_string(joint) + " of a " + std::to_string(joints) + "-joint skeleton");
    };
    for (std::size_t r = 0; r < clip->rotations.size(); ++r) {
      const RotationTrack& track = clip->rotations[r];
      const std::string what = "clip '" + clip->name + "' rotation track " + std::to_string(r);
      check_joint(track.joint, what);
      check_times(track.times, track.values.size(), what, out);
      if (track.times.empty()) continue;
      std::vector<float> values(4 * track.values.size());
      for (std::size_t k = 0; k < track.values.size(); ++k) {
        glm::quat q = track.values[k];
        const float len = glm::length(q);
        if (!std::isfinite(len) || len < 1e-6f) out.fail(what + ": key " + std::to_string(k) + " is not a rotation");
        q /= len;
        values[4 * k] = q.x, values[4 * k + 1] = q.y, values[4 * k + 2] = q.z, values[4 * k + 3] = q.w;
      }
      const int input = input_of(track.times);
      add_channel(input, out.add_accessor(values, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC4, 4, 0, false),
                  track.joint, "rotation");
    }
    for (std::size_t r = 0; r < clip->translations.size(); ++r) {
      const TranslationTrack& track = clip->translations[r];
      const std::string what = "clip '" + clip->name + "' translation track " + std::to_string(r);
      check_joint(track.joint, what);
      check_times(track.times, track.values.size(), what, out);
      if (track.times.empty()) continue;
      // H-Anim's translation is an offset of the joint's rest placement; the node's translation is absolute.
      const std::vector<double>& rest = model.nodes[track.joint].translation;
      std::vector<float> values(3 * track.values.size());
      for (std::size_t k = 0; k < track.values.size(); ++k) {
        if (!finite(track.values[k])) out.fail(what + ": key " + std::to_string(k) + " is not finite");
        for (int c = 0; c < 3; ++c) values[3 * k + c] = static_cast<float>(rest[c] + track.values[k][c]);
      }
      const int input = input_of(track.times);
      add_channel(input, out.add_accessor(values, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3, 0, false),
                  track.joint, "translation");
    }
    if (!anim.channels.empty()) model.animations.push_back(anim);
  }

  // --- file ----------------------------------------------------------------------------------------------------
  std::filesystem::path temp = path;
  temp += ".tmp" + std::to_string(::getpid());
  TempFile guard(temp);
  {
    std::ofstream file(temp, std::ios::binary | std::ios::trunc);
    if (!file) out.fail(std::string("cannot open for writing: ") + std::strerror(errno));
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, file, false, true)) out.fail("tinygltf could not serialise the model");
    file.flush();
    if (!file) out.fail(std::string("write failed: ") + std::strerror(errno));
    file.close();
    if (!file) out.fail(std::string("close failed: ") + std::strerror(errno));
  }
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(temp, ec);
  if (ec) out.fail("cannot stat the written file: " + ec.message());
  std::filesystem::rename(temp, path, ec);
  if (ec) out.fail("cannot rename " + temp.string() + " into place: " + ec.message());
  guard.commit();

  GltfExportStats stats;
  stats.vertices = vertices;
  stats.written_vertices = written;
  stats.triangles = mesh.triangle_count();
  stats.joints = joints;
  stats.keys = keys;
  stats.bytes = static_cast<std::size_t>(bytes);
  return stats;
}

}  // namespace strata
