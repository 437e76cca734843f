#include "io/gltf.h"

#include "components/humanoid_shape.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

// tinygltf is linked as Debian's shared library: including the header declares the API only (defining
// TINYGLTF_IMPLEMENTATION here would compile a second copy of the library into ours).
#include <tiny_gltf.h>

#include "io/mesh_check.h"

namespace strata {
namespace {

struct Trs {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 scale{1.0f};
  glm::mat4 matrix() const {
    return glm::translate(glm::mat4(1.0f), translation) * glm::mat4_cast(rotation) *
           glm::scale(glm::mat4(1.0f), scale);
  }
};

// Image decoding is irrelevant to a skin and costs time (CesiumMan embeds a JPEG): accept every image undecoded.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// In-memory loads have no directory: every attempt to reach the file system (an external buffer URI) fails.
bool no_file_exists(const std::string&, void*) { return false; }
std::string no_expand(const std::string& path, void*) { return path; }
bool no_read(std::vector<unsigned char>*, std::string* err, const std::string& path, void*) {
  if (err) *err += "external file '" + path + "' cannot be read when loading from memory. ";
  return false;
}
bool no_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not supported. ";
  return false;
}

std::uint32_t read_u32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);  // GLB is little-endian, as is every platform Strata builds for
  return v;
}

// The GLB container (12-byte header, then 8-byte-headed chunks: JSON first, an optional BIN) checked before
// tinygltf sees it, so a truncated or inconsistent file is refused with the byte offset at fault rather than
// tinygltf's generic message (or, in older releases, its out-of-bounds read).
void check_glb_framing(std::span<const std::uint8_t> b, const std::string& name) {
  auto fail = [&](std::size_t offset, const std::string& reason) {
    throw LoadError(name + ": byte " + std::to_string(offset) + ": " + reason);
  };
  const std::size_t size = b.size();
  if (size < 12) fail(size, "truncated GLB: " + std::to_string(size) + " bytes, the header alone is 12");
  if (const std::uint32_t version = read_u32(b.data() + 4); version != 2)
    fail(4, "GLB version " + std::to_string(version) + ", expected 2");
  if (const std::uint32_t length = read_u32(b.data() + 8); length != size)
    fail(8, "GLB header gives a length of " + std::to_string(length) + " bytes but the file has " +
                std::to_string(size) + (length > size ? " (truncated)" : ""));
  std::size_t offset = 12;
  for (int chunk = 0; offset < size; ++chunk) {
    if (size - offset < 8)
      fail(offset, "truncated GLB chunk header: " + std::to_string(size - offset) + " bytes left, need 8");
    const std::uint32_t length = read_u32(b.data() + offset);
    const std::uint32_t type = read_u32(b.data() + offset + 4);
    if (chunk == 0 && type != 0x4E4F534Au) fail(offset + 4, "the first GLB chunk is not JSON");
    if (length > size - offset - 8)
      fail(offset, "GLB chunk " + std::to_string(chunk) + " of " + std::to_string(length) + " bytes runs past the end of the file (" +
                       std::to_string(size - offset - 8) + " bytes left; truncated)");
    offset += 8 + length;
  }
  if (offset == 12) fail(12, "GLB has no JSON chunk");
}

class GltfReader {
 public:
  explicit GltfReader(const std::filesystem::path& path) : path_(path), name_(path.string()) {}
  GltfReader(std::span<const std::uint8_t> bytes, std::string_view name)
      : path_(std::string(name)), name_(name), memory_(bytes), in_memory_(true) {}

  ImportedBody read() {
    load_model();
    compute_parents();
    default_globals_ = globals_at_default();
    const int node = find_skinned_node();
    const tinygltf::Node& skinned = model_.nodes[node];
    if (static_cast<std::size_t>(skinned.mesh) >= model_.meshes.size())  // found by fuzzing
      fail("node " + std::to_string(node), "mesh " + std::to_string(skinned.mesh) + " does not exist");
    read_skin(skinned.skin);
    build_skeleton();
    ImportedBody body;
    read_mesh(model_.meshes[skinned.mesh], body);
    if (!model_.animations.empty()) bake_animation(model_.animations[0], body);
    body.skeleton = skeleton_;
    face_plus_z(body);
    validate_mesh(body.mesh, name_);
    return body;
  }

  // H-Anim's figure faces +Z with its left at +X, and the engine's limbs (knee flexion about +X), the walk
  // generator and the cameras assume it. glTF says only that +Y is up: CesiumMan faces +X. A humanoid rig (one with
  // l_hip and r_hip, by name or by shape) is turned about +Y until its left hip is at +X: positions, normals and
  // centres rotated, root translation keys rotated and rotation keys conjugated (exact: the turn is rigid).
  // Within 0.1 rad of a quarter turn the turn is snapped to it, so the usual cases keep exact coordinates.
  void face_plus_z(ImportedBody& body) {
    Skeleton& s = body.skeleton;
    const std::int32_t l_hip = s.find_joint("l_hip"), r_hip = s.find_joint("r_hip");
    if (l_hip < 0 || r_hip < 0) return;
    const glm::vec3 left = s.centers[l_hip] - s.centers[r_hip];
    if (!(left.x * left.x + left.z * left.z > 1e-8f)) return;
    float angle = std::atan2(left.z, left.x);
    const float quarter = 1.57079633f;
    const float snapped = std::round(angle / quarter) * quarter;
    if (std::abs(angle - snapped) < 0.1f) angle = snapped;
    if (std::abs(angle) < 1e-6f) return;
    const glm::quat turn = glm::angleAxis(angle, glm::vec3(0, 1, 0));
    auto rotate = [&](const glm::vec3& v) {
      glm::vec3 r = turn * v;
      // Quarter turns: drop the rounding noise of sin/cos so that x = 0.3 comes back as exactly 0.3, not 0.29999998.
      if (angle == snapped)
        for (int c = 0; c < 3; ++c) r[c] = std::abs(r[c]) < 1e-7f * (glm::length(v) + 1.0f) ? 0.0f : r[c];
      return r;
    };
    for (glm::vec3& p : body.mesh.positions) p = rotate(p);
    for (glm::vec3& n : body.mesh.normals) n = rotate(n);
    for (glm::vec3& c : s.centers) c = rotate(c);
    for (SkeletonSite& site : s.sites) site.position = rotate(site.position);
    for (AnimationClip& clip : body.clips) {
      for (TranslationTrack& t : clip.translations)
        for (glm::vec3& v : t.values) v = rotate(v);
      for (RotationTrack& t : clip.rotations)
        for (glm::quat& q : t.values) q = glm::normalize(turn * q * glm::conjugate(turn));
    }
    body.facing_turn = turn;
    body.warnings.push_back(name_ + ": turned " + std::to_string(static_cast<int>(std::lround(glm::degrees(angle)))) +
                            " deg about +Y to face +Z (H-Anim's forward)");
  }

 private:
  [[noreturn]] void fail(const std::string& what, const std::string& reason) const {
    throw LoadError(name_ + ": " + what + ": " + reason);
  }

  void load_model() {
    if (in_memory_) return load_model_from_memory();
    std::ifstream in(path_, std::ios::binary);
    if (!in) throw LoadError(name_ + ": cannot open file");
    char magic[4] = {};
    in.read(magic, 4);
    const bool binary = in.gcount() == 4 && std::memcmp(magic, "glTF", 4) == 0;
    in.close();
    if (binary) {
      std::ifstream whole(path_, std::ios::binary);
      const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(whole)), std::istreambuf_iterator<char>());
      check_glb_framing(bytes, name_);
    }
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    std::string err, warn;
    const bool ok = binary ? loader.LoadBinaryFromFile(&model_, &err, &warn, path_.string())
                           : loader.LoadASCIIFromFile(&model_, &err, &warn, path_.string());
    if (!ok) {
      std::replace(err.begin(), err.end(), '\n', ' ');
      throw LoadError(name_ + ": not a readable glTF 2.0 file: " + (err.empty() ? "unknown error" : err));
    }
  }

  void load_model_from_memory() {
    const bool binary = memory_.size() >= 4 && std::memcmp(memory_.data(), "glTF", 4) == 0;
    if (binary) check_glb_framing(memory_, name_);
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    loader.SetFsCallbacks({no_file_exists, no_expand, no_read, no_write, nullptr});
    std::string err, warn;
    // tinygltf takes an unsigned int size; larger inputs are not glTF files we can read anyway.
    if (memory_.size() > 0x7fffffffu) throw LoadError(name_ + ": not a readable glTF 2.0 file: larger than 2 GiB");
    const auto size = static_cast<unsigned int>(memory_.size());
    const bool ok = binary ? loader.LoadBinaryFromMemory(&model_, &err, &warn, memory_.data(), size, "")
                           : loader.LoadASCIIFromString(&model_, &err, &warn,
                                                        reinterpret_cast<const char*>(memory_.data()), size, "");
    if (!ok) {
      std::replace(err.begin(), err.end(), '\n', ' ');
      throw LoadError(name_ + ": not a readable glTF 2.0 file: " + (err.empty() ? "unknown error" : err));
    }
  }

  // --- accessors ---------------------------------------------------------------------------------------------
  struct View {
    const unsigned char* data = nullptr;
    std::size_t count = 0, stride = 0;
    int component_type = 0, components = 0;
    bool normalized = false;
  };

  View view(int index, int expected_type, const std::string& what) const {
    const std::string where = "accessor " + std::to_string(index) + " (" + what + ")";
    if (index < 0 || static_cast<std::size_t>(index) >= model_.accessors.size()) fail(where, "no such accessor");
    const tinygltf::Accessor& a = model_.accessors[index];
    if (a.sparse.isSparse) fail(where, "sparse accessors are not supported");
    if (expected_type != 0 && a.type != expected_type)
      fail(where, "type " + std::to_string(a.type) + ", expected " + std::to_string(expected_type));
    if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= model_.bufferViews.size())
      fail(where, "buffer view " + std::to_string(a.bufferView) + " does not exist");
    const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model_.buffers.size())
      fail(where, "buffer " + std::to_string(bv.buffer) + " does not exist");
    const std::vector<unsigned char>& buffer = model_.buffers[bv.buffer].data;
    View v;
    v.count = a.count;
    v.component_type = a.componentType;
    v.components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
    v.normalized = a.normalized;
    const int component_size = tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(a.componentType));
    if (v.components <= 0 || component_size <= 0) fail(where, "unknown type or component type");
    const std::size_t element = static_cast<std::size_t>(v.components) * component_size;
    v.stride = bv.byteStride ? bv.byteStride : element;
    // Every term is checked against the sizes before it is multiplied or added: a hostile count or offset must
    // not wrap size_t into a small, "valid" range.
    if (bv.byteOffset > buffer.size() || bv.byteLength > buffer.size() - bv.byteOffset)
      fail(where, "buffer view " + std::to_string(a.bufferView) + " (" + std::to_string(bv.byteLength) +
                      " bytes at offset " + std::to_string(bv.byteOffset) + ") lies outside its " +
                      std::to_string(buffer.size()) + "-byte buffer");
    const std::size_t limit = bv.byteLength;
    const bool fits = a.count == 0 ||
                      (a.byteOffset <= limit && element <= limit - a.byteOffset &&
                       (a.count - 1) <= (limit - a.byteOffset - element) / v.stride);
    if (!fits)
      fail(where, std::to_string(a.count) + " elements of " + std::to_string(element) + " bytes (stride " +
                      std::to_string(v.stride) + ", offset " + std::to_string(a.byteOffset) + ") read past a " +
                      std::to_string(bv.byteLength) + "-byte buffer view (out of range)");
    v.data = buffer.data() + bv.byteOffset + a.byteOffset;
    return v;
  }

  static double component(const View& v, std::size_t i, int c) {
    const unsigned char* p = v.data + i * v.stride;
    auto load = [&](auto type_tag) {
      using T = decltype(type_tag);
      T value;
      std::memcpy(&value, p + c * sizeof(T), sizeof(T));
      return value;
    };
    switch (v.component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: return load(float{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return v.normalized ? load(std::uint8_t{}) / 255.0 : load(std::uint8_t{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return v.normalized ? load(std::uint16_t{}) / 65535.0 : load(std::uint16_t{});
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return load(std::uint32_t{});
      case TINYGLTF_COMPONENT_TYPE_BYTE:
        return v.normalized ? std::max(load(std::int8_t{}) / 127.0, -1.0) : load(std::int8_t{});
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        return v.normalized ? std::max(load(std::int16_t{}) / 32767.0, -1.0) : load(std::int16_t{});
      default: return load(double{});
    }
  }

  // count x components floats, every one finite.
  std::vector<float> floats(int index, int expected_type, const std::string& what) const {
    const View v = view(index, expected_type, what);
    std::vector<float> out(v.count * v.components);
    for (std::size_t i = 0; i < v.count; ++i)
      for (int c = 0; c < v.components; ++c) {
        const double x = component(v, i, c);
        if (!std::isfinite(x))
          fail("accessor " + std::to_string(index) + " (" + what + ")",
               "element " + std::to_string(i) + " is not finite");
        out[i * v.components + c] = static_cast<float>(x);
      }
    return out;
  }

  std::vector<std::uint32_t> integers(int index, int expected_type, const std::string& what) const {
    const View v = view(index, expected_type, what);
    if (v.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        v.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        v.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail("accessor " + std::to_string(index) + " (" + what + ")", "expected unsigned integer components");
    View raw = v;
    raw.normalized = false;
    std::vector<std::uint32_t> out(v.count * v.components);
    for (std::size_t i = 0; i < v.count; ++i)
      for (int c = 0; c < v.components; ++c)
        out[i * v.components + c] = static_cast<std::uint32_t>(component(raw, i, c));
    return out;
  }

  // --- nodes -------------------------------------------------------------------------------------------------
  void compute_parents() {
    const std::size_t n = model_.nodes.size();
    parent_.assign(n, -1);
    default_trs_.resize(n);
    uses_matrix_.assign(n, false);
    for (std::size_t i = 0; i < n; ++i) {
      const tinygltf::Node& node = model_.nodes[i];
      for (int child : node.children) {
        if (child < 0 || static_cast<std::size_t>(child) >= n)
          fail("node " + std::to_string(i), "child " + std::to_string(child) + " does not exist");
        if (parent_[child] >= 0)
          fail("node " + std::to_string(child), "has two parents (" + std::to_string(parent_[child]) + " and " +
                                                    std::to_string(i) + ")");
        parent_[child] = static_cast<int>(i);
      }
      Trs& trs = default_trs_[i];
      auto finite = [&](const std::vector<double>& values, const char* field) {
        for (double x : values)
          if (!std::isfinite(x)) fail("node " + std::to_string(i), std::string(field) + " is not finite");
      };
      finite(node.matrix, "matrix");
      finite(node.translation, "translation");
      finite(node.rotation, "rotation");
      finite(node.scale, "scale");
      if (node.matrix.size() == 16) {
        uses_matrix_[i] = true;
        glm::dmat4 m;
        std::copy(node.matrix.begin(), node.matrix.end(), glm::value_ptr(m));  // both column-major
        matrix_[i] = glm::mat4(m);
      }
      if (node.translation.size() == 3)
        trs.translation = glm::vec3(node.translation[0], node.translation[1], node.translation[2]);
      if (node.rotation.size() == 4)
        trs.rotation = glm::normalize(glm::quat(static_cast<float>(node.rotation[3]), static_cast<float>(node.rotation[0]),
                                                static_cast<float>(node.rotation[1]), static_cast<float>(node.rotation[2])));
      if (node.scale.size() == 3) trs.scale = glm::vec3(node.scale[0], node.scale[1], node.scale[2]);
    }
    // A cycle would make a node its own ancestor. Each node's parent chain is walked once (state: 0 unseen, 1 on
    // the current walk, 2 known acyclic), so a deep chain costs O(n), not O(n * depth).
    std::vector<char> state(n, 0);
    std::vector<int> walk;
    for (std::size_t i = 0; i < n; ++i) {
      walk.clear();
      for (int p = static_cast<int>(i); p >= 0 && state[p] != 2; p = parent_[p]) {
        if (state[p] == 1) fail("node " + std::to_string(p), "the node tree has a cycle");
        state[p] = 1;
        walk.push_back(p);
      }
      for (int p : walk) state[p] = 2;
    }
  }

  // Globals of every node from per-node local matrices (parents resolved on demand).
  std::vector<glm::mat4> globals(const std::vector<glm::mat4>& locals) const {
    const std::size_t n = locals.size();
    std::vector<glm::mat4> out(n);
    std::vector<char> done(n, 0);
    // Iterative: a recursive walk up the parents overflows the stack on a deep (hostile) node chain.
    std::vector<int> chain;
    for (std::size_t i = 0; i < n; ++i) {
      for (int p = static_cast<int>(i); p >= 0 && !done[p]; p = parent_[p]) chain.push_back(p);
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        const int k = *it;
        out[k] = parent_[k] >= 0 ? out[parent_[k]] * locals[k] : locals[k];
        done[k] = 1;
      }
      chain.clear();
    }
    return out;
  }

  std::vector<glm::mat4> globals_at_default() const {
    std::vector<glm::mat4> locals(model_.nodes.size());
    for (std::size_t i = 0; i < locals.size(); ++i)
      locals[i] = uses_matrix_[i] ? matrix_.at(i) : default_trs_[i].matrix();
    return globals(locals);
  }

  int find_skinned_node() const {
    auto skinned = [&](int i) { return model_.nodes[i].mesh >= 0 && model_.nodes[i].skin >= 0; };
    std::vector<int> roots;
    const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (static_cast<std::size_t>(scene) < model_.scenes.size()) roots = model_.scenes[scene].nodes;
    // Depth-first, children in order, with an explicit stack (no recursion depth for a hostile tree to exhaust).
    auto search = [&](int root) {
      std::vector<int> stack{root};
      while (!stack.empty()) {
        const int i = stack.back();
        stack.pop_back();
        if (i < 0 || static_cast<std::size_t>(i) >= model_.nodes.size()) continue;
        if (skinned(i)) return i;
        const std::vector<int>& children = model_.nodes[i].children;
        stack.insert(stack.end(), children.rbegin(), children.rend());
      }
      return -1;
    };
    for (int r : roots)
      if (const int found = search(r); found >= 0) return found;
    for (std::size_t i = 0; i < model_.nodes.size(); ++i)  // skinned node outside the scene: still usable
      if (skinned(static_cast<int>(i))) return static_cast<int>(i);
    throw LoadError(name_ + ": no skinned mesh (no node has both a mesh and a skin)");
  }

  void read_skin(int index) {
    if (index < 0 || static_cast<std::size_t>(index) >= model_.skins.size())
      fail("skin " + std::to_string(index), "does not exist");
    const tinygltf::Skin& skin = model_.skins[index];
    if (skin.joints.empty()) fail("skin " + std::to_string(index), "has no joints");
    if (skin.joints.size() > 32767) fail("skin " + std::to_string(index), "has too many joints");
    for (int j : skin.joints)
      if (j < 0 || static_cast<std::size_t>(j) >= model_.nodes.size())
        fail("skin " + std::to_string(index), "joint node " + std::to_string(j) + " does not exist");
    skin_joints_ = skin.joints;
    ibm_.assign(skin_joints_.size(), glm::mat4(1.0f));
    if (skin.inverseBindMatrices >= 0) {
      const std::vector<float> m = floats(skin.inverseBindMatrices, TINYGLTF_TYPE_MAT4, "inverseBindMatrices");
      if (m.size() < 16 * ibm_.size())
        fail("accessor " + std::to_string(skin.inverseBindMatrices),
             "has " + std::to_string(m.size() / 16) + " matrices for " + std::to_string(ibm_.size()) + " joints");
      for (std::size_t k = 0; k < ibm_.size(); ++k) ibm_[k] = glm::make_mat4(m.data() + 16 * k);
    }
  }

  void build_skeleton() {
    const std::size_t k_count = skin_joints_.size();
    std::vector<int> skin_index_of_node(model_.nodes.size(), -1);
    for (std::size_t k = 0; k < k_count; ++k) {
      if (skin_index_of_node[skin_joints_[k]] >= 0)
        fail("skin", "node " + std::to_string(skin_joints_[k]) + " is listed twice");
      skin_index_of_node[skin_joints_[k]] = static_cast<int>(k);
    }
    // Parent in skin terms: the nearest ancestor node that is a joint of this skin.
    std::vector<int> skin_parent(k_count, -1);
    std::vector<std::vector<int>> children(k_count);
    std::vector<int> roots;
    for (std::size_t k = 0; k < k_count; ++k) {
      for (int p = parent_[skin_joints_[k]]; p >= 0; p = parent_[p])
        if (skin_index_of_node[p] >= 0) {
          skin_parent[k] = skin_index_of_node[p];
          break;
        }
      if (skin_parent[k] < 0)
        roots.push_back(static_cast<int>(k));
      else
        children[skin_parent[k]].push_back(static_cast<int>(k));
    }
    const bool synthetic_root = roots.size() > 1;
    Skeleton& s = skeleton_;
    s.name = path_.stem().string();
    s.source = name_;
    s.naming = JointNaming::Mixed;
    joint_of_skin_.assign(k_count, -1);
    skin_of_joint_.clear();
    auto add = [&](const std::string& name, int parent, glm::vec3 center, int skin_k) {
      s.joint_names.push_back(name);
      s.source_joint_names.push_back(name);
      s.parents.push_back(parent);
      s.centers.push_back(center);
      s.limits.emplace_back();
      s.stiffness.emplace_back(1.0f);
      skin_of_joint_.push_back(skin_k);
      return static_cast<int>(s.joint_names.size() - 1);
    };
    if (synthetic_root) add("skin_root", -1, glm::vec3(0.0f), -1);
    // Depth-first preorder (parents first) with an explicit stack: a recursive visit overflows on a deep chain.
    std::vector<std::pair<int, int>> stack;  // (skin joint, skeleton parent)
    for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.emplace_back(*r, synthetic_root ? 0 : -1);
    while (!stack.empty()) {
      const auto [k, parent] = stack.back();
      stack.pop_back();
      const tinygltf::Node& node = model_.nodes[skin_joints_[k]];
      const std::string name = node.name.empty() ? "joint_" + std::to_string(k) : node.name;
      const glm::vec3 center(default_globals_[skin_joints_[k]][3]);
      if (!std::isfinite(center.x) || !std::isfinite(center.y) || !std::isfinite(center.z))
        fail("node " + std::to_string(skin_joints_[k]), "its default-pose position is not finite");
      const int j = add(name, parent, center, k);
      joint_of_skin_[k] = j;
      for (auto c = children[k].rbegin(); c != children[k].rend(); ++c) stack.emplace_back(*c, j);
    }
    // A skin's joints carry the exporter's names, or none (CesiumMan): where they are not H-Anim's, the limbs, the
    // walk generator and retargeting find them by a known family's names (Mixamo, HumanIK, ...), else by the
    // skeleton's shape (components/humanoid_shape.h). A skin that is no humanoid (RiggedSimple's two-bone
    // cylinder) keeps its names and plays its own clips.
    name_humanoid_joints(s);
  }

  void read_mesh(const tinygltf::Mesh& gmesh, ImportedBody& body) {
    struct Prim {
      const tinygltf::Primitive* p;
      std::size_t index;
    };
    std::vector<Prim> prims;
    for (std::size_t i = 0; i < gmesh.primitives.size(); ++i) {
      const tinygltf::Primitive& p = gmesh.primitives[i];
      const auto& a = p.attributes;
      if (p.mode != TINYGLTF_MODE_TRIANGLES || !a.count("POSITION") || !a.count("JOINTS_0") || !a.count("WEIGHTS_0")) {
        body.warnings.push_back(name_ + ": primitive " + std::to_string(i) + " skipped (not skinned triangles)");
        continue;
      }
      prims.push_back({&p, i});
    }
    if (prims.empty()) throw LoadError(name_ + ": no skinned mesh (no triangle primitive with JOINTS_0/WEIGHTS_0)");
    bool all_normals = true, all_uvs = true;
    for (const Prim& pr : prims) {
      all_normals = all_normals && pr.p->attributes.count("NORMAL");
      all_uvs = all_uvs && pr.p->attributes.count("TEXCOORD_0");
    }

    Mesh& mesh = body.mesh;
    SkinBinding& skin = body.skin;
    mesh.name = gmesh.name.empty() ? path_.stem().string() : gmesh.name;
    std::vector<glm::vec3> bind_normals;
    std::vector<glm::vec3> bind_positions;
    for (const Prim& pr : prims) {
      const auto& a = pr.p->attributes;
      const std::size_t base = bind_positions.size();
      const std::vector<float> pos = floats(a.at("POSITION"), TINYGLTF_TYPE_VEC3, "POSITION");
      const std::size_t count = pos.size() / 3;
      auto check_count = [&](std::size_t got, const char* what, int accessor) {
        if (got != count)
          fail("accessor " + std::to_string(accessor) + " (" + what + ")",
               std::to_string(got) + " elements for " + std::to_string(count) + " vertices");
      };
      for (std::size_t i = 0; i < count; ++i) bind_positions.emplace_back(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      if (all_normals) {
        const std::vector<float> nrm = floats(a.at("NORMAL"), TINYGLTF_TYPE_VEC3, "NORMAL");
        check_count(nrm.size() / 3, "NORMAL", a.at("NORMAL"));
        for (std::size_t i = 0; i < count; ++i) bind_normals.emplace_back(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]);
      }
      if (all_uvs) {
        const std::vector<float> uv = floats(a.at("TEXCOORD_0"), TINYGLTF_TYPE_VEC2, "TEXCOORD_0");
        check_count(uv.size() / 2, "TEXCOORD_0", a.at("TEXCOORD_0"));
        // glTF's v runs down from the image's top; Mesh's, as OBJ's and OpenGL's, up from its bottom.
        for (std::size_t i = 0; i < count; ++i) mesh.uvs.emplace_back(uv[2 * i], 1.0f - uv[2 * i + 1]);
      }
      const std::vector<std::uint32_t> joints = integers(a.at("JOINTS_0"), TINYGLTF_TYPE_VEC4, "JOINTS_0");
      check_count(joints.size() / 4, "JOINTS_0", a.at("JOINTS_0"));
      const std::vector<float> weights = floats(a.at("WEIGHTS_0"), TINYGLTF_TYPE_VEC4, "WEIGHTS_0");
      check_count(weights.size() / 4, "WEIGHTS_0", a.at("WEIGHTS_0"));
      std::size_t renormalised = 0;
      for (std::size_t i = 0; i < count; ++i) {
        std::array<std::int16_t, kMaxInfluences> js{};
        std::array<float, kMaxInfluences> ws{};
        float sum = 0.0f;
        for (int c = 0; c < 4; ++c) {
          const float w = weights[4 * i + c];
          if (w < 0.0f)
            fail("accessor " + std::to_string(a.at("WEIGHTS_0")) + " (WEIGHTS_0)",
                 "vertex " + std::to_string(i) + " has a negative weight");
          if (w == 0.0f) continue;
          const std::uint32_t k = joints[4 * i + c];
          if (k >= skin_joints_.size())
            fail("accessor " + std::to_string(a.at("JOINTS_0")) + " (JOINTS_0)",
                 "vertex " + std::to_string(i) + " uses joint " + std::to_string(k) + " of a " +
                     std::to_string(skin_joints_.size()) + "-joint skin");
          js[c] = static_cast<std::int16_t>(joint_of_skin_[k]);
          ws[c] = w;
          sum += w;
        }
        if (sum <= 0.0f)
          fail("accessor " + std::to_string(a.at("WEIGHTS_0")) + " (WEIGHTS_0)",
               "vertex " + std::to_string(i) + " has no weight");
        if (std::abs(sum - 1.0f) > 1e-3f) ++renormalised;
        for (float& w : ws) w /= sum;
        skin.joints.push_back(js);
        skin.weights.push_back(ws);
      }
      if (renormalised)
        body.warnings.push_back(name_ + ": primitive " + std::to_string(pr.index) + ": " +
                                std::to_string(renormalised) + " vertices had weight sums off 1; normalised");

      if (pr.p->indices >= 0) {
        const std::vector<std::uint32_t> idx = integers(pr.p->indices, TINYGLTF_TYPE_SCALAR, "indices");
        if (idx.size() % 3) fail("accessor " + std::to_string(pr.p->indices), "index count is not a multiple of 3");
        for (std::uint32_t i : idx) {
          if (i >= count)
            fail("accessor " + std::to_string(pr.p->indices) + " (indices)",
                 "index " + std::to_string(i) + " out of range (" + std::to_string(count) + " vertices)");
          mesh.triangles.push_back(static_cast<std::uint32_t>(base + i));
        }
      } else {
        for (std::size_t i = 0; i + 2 < count; i += 3)
          for (int c = 0; c < 3; ++c) mesh.triangles.push_back(static_cast<std::uint32_t>(base + i + c));
      }
      mesh.part.insert(mesh.part.end(), count, static_cast<std::uint16_t>(mesh.part_names.size()));
      mesh.part_names.push_back(prims.size() == 1 ? mesh.name : mesh.name + "_" + std::to_string(pr.index));
    }

    // The rest mesh is the default pose: v = sum_i w_i N_k IBM_k v_bind (per glTF the mesh node's own transform
    // plays no part).
    std::vector<glm::mat4> joint_matrix(skeleton_.joint_count(), glm::mat4(1.0f));
    for (std::size_t j = 0; j < joint_matrix.size(); ++j)
      if (skin_of_joint_[j] >= 0)
        joint_matrix[j] = default_globals_[skin_joints_[skin_of_joint_[j]]] * ibm_[skin_of_joint_[j]];
    mesh.positions.resize(bind_positions.size());
    if (all_normals) mesh.normals.resize(bind_positions.size());
    for (std::size_t v = 0; v < bind_positions.size(); ++v) {
      glm::mat4 m(0.0f);
      for (int c = 0; c < kMaxInfluences; ++c) m += skin.weights[v][c] * joint_matrix[skin.joints[v][c]];
      mesh.positions[v] = glm::vec3(m * glm::vec4(bind_positions[v], 1.0f));
      if (all_normals) {
        const glm::vec3 n = glm::inverseTranspose(glm::mat3(m)) * bind_normals[v];
        const float len = glm::length(n);
        mesh.normals[v] = len > 1e-20f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
      }
    }
    if (!all_normals) compute_normals(mesh);
  }

  // --- animation -----------------------------------------------------------------------------------------------
  struct Channel {
    int node = -1;
    enum Path { Translation, Rotation, Scale } path = Translation;
    enum Interp { Linear, Step, Cubic } interp = Linear;
    std::vector<float> times, values;  // values: 3 or 4 per key (x3 for cubic: in-tangent, value, out-tangent)
  };

  glm::vec4 channel_value(const Channel& ch, float t) const {
    const int width = ch.path == Channel::Rotation ? 4 : 3;
    const int stride = ch.interp == Channel::Cubic ? 3 : 1;  // elements per key
    auto element = [&](std::size_t key, int which) {  // which: 0 in-tangent, 1 value, 2 out-tangent (cubic)
      const std::size_t e = key * stride + (ch.interp == Channel::Cubic ? which : 0);
      glm::vec4 out(0.0f);
      for (int c = 0; c < width; ++c) out[c] = ch.values[e * width + c];
      return out;
    };
    const std::vector<float>& ts = ch.times;
    if (t <= ts.front()) return element(0, 1);
    if (t >= ts.back()) return element(ts.size() - 1, 1);
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
    const float dt = ts[k + 1] - ts[k];
    const float s = dt > 0.0f ? (t - ts[k]) / dt : 0.0f;
    if (ch.interp == Channel::Step) return element(k, 1);
    if (ch.interp == Channel::Cubic) {
      const float s2 = s * s, s3 = s2 * s;
      return (2 * s3 - 3 * s2 + 1) * element(k, 1) + (s3 - 2 * s2 + s) * dt * element(k, 2) +
             (-2 * s3 + 3 * s2) * element(k + 1, 1) + (s3 - s2) * dt * element(k + 1, 0);
    }
    const glm::vec4 a = element(k, 1), b = element(k + 1, 1);
    if (ch.path != Channel::Rotation) return a + s * (b - a);
    const glm::quat q = glm::slerp(glm::quat(a.w, a.x, a.y, a.z), glm::quat(b.w, b.x, b.y, b.z), s);
    return glm::vec4(q.x, q.y, q.z, q.w);
  }

  void bake_animation(const tinygltf::Animation& anim, ImportedBody& body) {
    std::vector<Channel> channels;
    for (std::size_t c = 0; c < anim.channels.size(); ++c) {
      const tinygltf::AnimationChannel& gc = anim.channels[c];
      const std::string where = "animation channel " + std::to_string(c);
      Channel ch;
      if (gc.target_path == "translation") ch.path = Channel::Translation;
      else if (gc.target_path == "rotation") ch.path = Channel::Rotation;
      else if (gc.target_path == "scale") ch.path = Channel::Scale;
      else continue;  // morph target weights do not move joints
      if (gc.target_node < 0 || static_cast<std::size_t>(gc.target_node) >= model_.nodes.size())
        fail(where, "target node " + std::to_string(gc.target_node) + " does not exist");
      if (gc.sampler < 0 || static_cast<std::size_t>(gc.sampler) >= anim.samplers.size())
        fail(where, "sampler " + std::to_string(gc.sampler) + " does not exist");
      const tinygltf::AnimationSampler& sampler = anim.samplers[gc.sampler];
      ch.node = gc.target_node;
      ch.interp = sampler.interpolation == "STEP"          ? Channel::Step
                  : sampler.interpolation == "CUBICSPLINE" ? Channel::Cubic
                                                           : Channel::Linear;
      ch.times = floats(sampler.input, TINYGLTF_TYPE_SCALAR, "animation input");
      const int width = ch.path == Channel::Rotation ? 4 : 3;
      ch.values = floats(sampler.output, width == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, "animation output");
      if (ch.times.empty()) fail("accessor " + std::to_string(sampler.input), "animation input has no keys");
      for (std::size_t k = 1; k < ch.times.size(); ++k)
        if (!(ch.times[k] > ch.times[k - 1]))
          fail("accessor " + std::to_string(sampler.input), "key times are not strictly increasing");
      const std::size_t expected = ch.times.size() * width * (ch.interp == Channel::Cubic ? 3 : 1);
      if (ch.values.size() != expected)
        fail("accessor " + std::to_string(sampler.output),
             std::to_string(ch.values.size() / width) + " output elements for " + std::to_string(ch.times.size()) +
                 " keys");
      channels.push_back(std::move(ch));
    }
    if (channels.empty()) return;

    std::vector<float> times;
    for (const Channel& ch : channels) times.insert(times.end(), ch.times.begin(), ch.times.end());
    std::sort(times.begin(), times.end());
    times.erase(std::unique(times.begin(), times.end(), [](float a, float b) { return b - a < 1e-6f; }), times.end());

    // Baking evaluates every node at every key time. A hostile file can pair 10^5 key times with 10^5 nodes from
    // well under a megabyte; refuse what no body animation needs rather than hang (CesiumMan: 48 x 22).
    constexpr double kBakeBudget = 5e7;
    if (static_cast<double>(times.size()) * static_cast<double>(model_.nodes.size() + skeleton_.joint_count()) > kBakeBudget)
      fail("animation '" + (anim.name.empty() ? std::string("animation_0") : anim.name) + "'",
           std::to_string(times.size()) + " key times x " + std::to_string(model_.nodes.size()) +
               " nodes is too large to bake");

    // An animated node defined by `matrix` (not allowed by glTF, but seen) is decomposed once into TRS.
    std::vector<Trs> base = default_trs_;
    for (const Channel& ch : channels)
      if (uses_matrix_[ch.node]) {
        const glm::mat4& m = matrix_.at(ch.node);
        base[ch.node].translation = glm::vec3(m[3]);
        base[ch.node].scale = glm::vec3(glm::length(glm::vec3(m[0])), glm::length(glm::vec3(m[1])),
                                        glm::length(glm::vec3(m[2])));
        base[ch.node].rotation = glm::quat_cast(glm::mat3(glm::vec3(m[0]) / base[ch.node].scale.x,
                                                          glm::vec3(m[1]) / base[ch.node].scale.y,
                                                          glm::vec3(m[2]) / base[ch.node].scale.z));
      }
    std::vector<char> animated(model_.nodes.size(), 0);
    for (const Channel& ch : channels) animated[ch.node] = 1;

    const std::size_t nj = skeleton_.joint_count();
    std::vector<glm::mat4> default_inverse(nj, glm::mat4(1.0f));
    for (std::size_t j = 0; j < nj; ++j)
      if (skin_of_joint_[j] >= 0) default_inverse[j] = glm::inverse(default_globals_[skin_joints_[skin_of_joint_[j]]]);

    AnimationClip clip;
    clip.name = anim.name.empty() ? "animation_0" : anim.name;
    clip.duration = times.back();
    clip.loop = true;
    clip.rotations.resize(nj);
    for (std::size_t j = 0; j < nj; ++j) clip.rotations[j].joint = static_cast<std::int32_t>(j);
    clip.translations.resize(1);
    clip.translations[0].joint = 0;
    float max_residual = 0.0f;
    std::vector<glm::mat4> locals(model_.nodes.size()), g(nj);
    for (float t : times) {
      std::vector<Trs> trs = base;
      for (const Channel& ch : channels) {
        const glm::vec4 v = channel_value(ch, t);
        if (ch.path == Channel::Translation) trs[ch.node].translation = glm::vec3(v);
        else if (ch.path == Channel::Scale) trs[ch.node].scale = glm::vec3(v);
        else trs[ch.node].rotation = glm::normalize(glm::quat(v.w, v.x, v.y, v.z));
      }
      for (std::size_t i = 0; i < locals.size(); ++i)
        locals[i] = uses_matrix_[i] && !animated[i] ? matrix_.at(i) : trs[i].matrix();
      const std::vector<glm::mat4> global = globals(locals);
      for (std::size_t j = 0; j < nj; ++j) {
        g[j] = skin_of_joint_[j] >= 0 ? global[skin_joints_[skin_of_joint_[j]]] * default_inverse[j]
                                      : glm::mat4(1.0f);
        const int p = skeleton_.parents[j];
        const glm::mat4 local = p >= 0 ? glm::inverse(g[p]) * g[j] : g[j];
        // Rotation part; columns normalised so a near-unit scale does not leak into the quaternion.
        const glm::mat3 r(glm::normalize(glm::vec3(local[0])), glm::normalize(glm::vec3(local[1])),
                          glm::normalize(glm::vec3(local[2])));
        glm::quat q = glm::normalize(glm::quat_cast(r));
        RotationTrack& track = clip.rotations[j];
        if (!track.values.empty() && glm::dot(track.values.back(), q) < 0.0f) q = -q;
        track.times.push_back(t);
        track.values.push_back(q);
        const glm::vec3 c = skeleton_.centers[j];
        if (p < 0) {
          clip.translations[0].times.push_back(t);
          clip.translations[0].values.push_back(glm::vec3(g[j] * glm::vec4(c, 1.0f)) - c);
        } else {
          // What the H-Anim chain would put at c_j versus where the glTF puts it.
          const glm::vec3 expected = c - glm::mat3_cast(q) * c;
          max_residual = std::max(max_residual, glm::length(glm::vec3(local[3]) - expected));
        }
      }
    }
    // A singular node transform (a zero scale) has no inverse: the baked keys would be NaN. No NaN leaves a loader.
    auto finite = [](auto v) {
      for (int c = 0; c < v.length(); ++c)
        if (!std::isfinite(v[c])) return false;
      return true;
    };
    for (const RotationTrack& track : clip.rotations)
      for (std::size_t k = 0; k < track.values.size(); ++k)
        if (!finite(track.values[k]))
          fail("animation '" + clip.name + "'", "joint " + std::to_string(track.joint) + " at t=" +
                                                    std::to_string(track.times[k]) +
                                                    " s bakes to a non-finite rotation (singular node transform)");
    for (const glm::vec3& t : clip.translations[0].values)
      if (!finite(t)) fail("animation '" + clip.name + "'", "the root bakes to a non-finite translation");
    body.warnings.push_back(name_ + ": animation '" + clip.name + "' baked at " + std::to_string(times.size()) +
                            " key times; largest non-root translation residual " + std::to_string(max_residual) +
                            " m");
    body.clips.push_back(std::move(clip));
  }

  std::filesystem::path path_;
  std::string name_;
  std::span<const std::uint8_t> memory_;
  bool in_memory_ = false;
  tinygltf::Model model_;
  std::vector<int> parent_;
  std::vector<Trs> default_trs_;
  std::vector<bool> uses_matrix_;
  std::unordered_map<std::size_t, glm::mat4> matrix_;
  std::vector<glm::mat4> default_globals_;
  std::vector<int> skin_joints_;       // skin joint k -> node
  std::vector<glm::mat4> ibm_;         // per skin joint
  std::vector<int> joint_of_skin_;     // skin joint k -> skeleton joint
  std::vector<int> skin_of_joint_;     // skeleton joint -> skin joint k (-1 for a synthetic root)
  Skeleton skeleton_;
};

}  // namespace

ImportedBody load_gltf(const std::filesystem::path& path) { return GltfReader(path).read(); }

ImportedBody load_gltf_memory(std::span<const std::uint8_t> bytes, std::string_view source_name) {
  return GltfReader(bytes, source_name).read();
}

}  // namespace strata
