// The X3D H-Anim encoding (ISO 19774 nodes in X3D XML; tech-brief.md sections 2.1-2.6, data-README.md section 2).
//
// What the real files taught us, and the policies that follow:
// * Site `translation` is the site's absolute rest position in humanoid coordinates. X3D semantics say the same
//   thing: a Site inside a Joint inside ... is transformed by each Joint's T(c)·R·T(-c), which is identity at rest.
//   Checked on Humanoid1.x3d (l_calcaneus_posterior_pt 0.0974 0.0259 -0.1171 = the 200x heel landmark) and Joe
//   (l_iliocristale at y 1.065, pelvis height). A Site without translation sits at the origin (X3D's default);
//   46 of StandardHumanoid's sites are like that and are kept as written.
// * DEF must precede USE in document order (X3D rule); a USE of a DEF not seen yet is reported as unknown.
// * A joint reached twice in the skeleton tree through USE (Joe lists HumanoidRoot twice in `skeleton`) is kept
//   once, with a warning; a joint that reaches itself (a USE of one of its ancestors) is a cycle and an error.
// * The HAnimHumanoid's own transform (translation, rotation, scale, scaleOrientation, center: X3D Transform
//   semantics) and the document's length UNIT are baked into every rest position (joint centres, sites, segment
//   centres of mass, skin points) and into the animation: translation keys take the transform's linear part,
//   rotation keys are conjugated by its rotation. Keeping the transform as a separate placement was the
//   alternative; every consumer (camera framing, walker spacing, the walk generator's leg lengths) would then
//   have to apply it, and a 0.0225-scaled file proved one of them would forget. With a non-uniform scale a
//   rotation key cannot be baked exactly; that case loads with a warning.
// * A joint with a DEF and no name takes the H-Anim joint name its DEF ends in (DEF='hanim_l_hip' -> l_hip), with
//   a warning; a DEF that ends in no H-Anim name is an error, as is a derived name another joint already has.
// * Segment geometry (LOA-1 figures are built from rigid per-segment meshes): IndexedFaceSet and IndexedTriangleSet
//   Shapes inside an HAnimSegment, through any Transforms and Groups, are read in humanoid coordinates (the
//   joints' rest transforms are identity). A file without a skin gets them as its skin, every vertex weighted 1 to
//   its segment's joint, so they are drawn and move as rigid parts; with a skin, the skin wins and they are ignored
//   with a warning. Other geometry (lines, primitives) is not drawn.
// * Joint translation/rotation are ignored (H-Anim's rest pose is identity with absolute centres); a non-identity
//   value is reported as a warning so a file authored with relative offsets does not load silently wrong.
#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include "io/hanim_readers.h"

namespace strata::detail {
namespace {

bool is_tag(pugi::xml_node n, std::string_view tag) { return std::string_view(n.name()) == tag; }

struct RawSkin {
  pugi::xml_node node;  // the joint element, for messages
  std::vector<std::int64_t> indices;
  std::optional<std::vector<float>> weights;
};

// An interpolator's keys converted to seconds, parsed once however many joints it drives.
struct ParsedInterpolator {
  std::vector<float> times;
  std::vector<glm::quat> rotations;
  std::vector<glm::vec3> positions;
};

class X3dReader {
 public:
  explicit X3dReader(const xml::Document& doc) : doc_(doc), sk_(asset_.skeleton) {}

  HumanoidAsset read() {
    asset_.format = HumanoidFormat::X3D;
    sk_.source = doc_.source_name();
    collect(doc_.root());
    if (humanoids_.empty()) doc_.fail(doc_.root(), "no HAnimHumanoid found");
    humanoid_ = resolve(humanoids_.front());
    if (humanoids_.size() > 1)
      sk_.warnings.push_back(doc_.warning(humanoids_[1], "more than one HAnimHumanoid; only the first is loaded"));
    read_humanoid();
    finalize_joint_names(sk_);
    read_skin();
    segments_as_skin();
    read_animation();
    apply_humanoid_transform();
    return std::move(asset_);
  }

 private:
  // ---- document-wide pass: DEF table, and the nodes the later passes need -----------------------------------
  void collect(pugi::xml_node n) {
    const pugi::xml_attribute def = n.attribute("DEF");
    const pugi::xml_attribute use = n.attribute("USE");
    if (def && use) doc_.fail(n, "has both DEF and USE");
    if (def) {
      const auto [it, inserted] = defs_.emplace(def.value(), n);
      if (!inserted)
        doc_.fail(n, std::string("duplicate DEF '") + def.value() + "' (first at line " +
                         std::to_string(doc_.line_of(it->second)) + ")");
    }
    if (use && defs_.find(use.value()) == defs_.end())
      doc_.fail(n, std::string("USE of unknown DEF '") + use.value() + "'");
    if (is_tag(n, "HAnimHumanoid")) humanoids_.push_back(n);
    if (is_tag(n, "unit")) read_unit(n);
    if (!use && is_tag(n, "TimeSensor")) time_sensors_.push_back(n);
    if (is_tag(n, "ROUTE")) routes_.push_back(n);
    for (pugi::xml_node child : n.children())
      if (child.type() == pugi::node_element) collect(child);
  }

  // X3D 3.3's UNIT statement: <head><unit category='length' name='inch' conversionFactor='0.0254'/></head>. Length
  // and angle scale what the reader takes in; other categories (mass, force) are not read by us.
  void read_unit(pugi::xml_node n) {
    const std::string_view category = n.attribute("category").value();
    if (category != "length" && category != "angle") return;
    const std::optional<float> factor = xml::float_attr(doc_, n, "conversionFactor");
    if (!factor || !(*factor > 0.0f)) doc_.fail(n, "conversionFactor must be a positive number");
    (category == "length" ? metres_per_unit_ : radians_per_unit_) = *factor;
  }

  pugi::xml_node resolve(pugi::xml_node n) const {
    const pugi::xml_attribute use = n.attribute("USE");
    if (!use) return n;
    return defs_.at(use.value());  // collect() guarantees presence
  }

  // ---- the humanoid and its skeleton -------------------------------------------------------------------------
  void read_humanoid() {
    sk_.name = humanoid_.attribute("name").value();
    if (sk_.name.empty()) sk_.name = humanoid_.attribute("DEF").value();

    std::vector<pugi::xml_node> loose;  // Sites/Segments defined at humanoid level
    for (pugi::xml_node child : humanoid_.children()) {
      if (child.type() != pugi::node_element) continue;
      const std::string_view field = child.attribute("containerField").value();
      if (is_tag(child, "HAnimJoint")) {
        // X3D's default containerField for a Joint under a Humanoid is `skeleton`; 1.1 called it humanoidBody.
        if (field.empty() || field == "skeleton" || field == "humanoidBody") {
          read_body_root(child);
        } else if (!child.attribute("USE")) {
          sk_.warnings.push_back(doc_.warning(child, "joint defined in the '" + std::string(field) +
                                                         "' list is not part of the skeleton; ignored"));
        }
      } else if (field == "skin") {
        skin_node_ = child;
      } else if (field == "skinCoord") {
        skin_coord_ = resolve(child);
      } else if ((is_tag(child, "HAnimSite") || is_tag(child, "HAnimSegment")) && !child.attribute("USE")) {
        loose.push_back(child);
      }
    }
    if (sk_.parents.empty()) doc_.fail(humanoid_, "no skeleton root joint (containerField='skeleton')");

    // A Site or Segment defined directly in the humanoid moves with the whole body: hang it from the root.
    for (pugi::xml_node n : loose) {
      if (is_tag(n, "HAnimSite"))
        add_site(n, 0);
      else
        add_segment(n, 0);
    }
  }

  void read_body_root(pugi::xml_node node) {
    const pugi::xml_node target = resolve(node);
    if (joint_index_of(target) >= 0) {
      sk_.warnings.push_back(doc_.warning(node, "joint is already in the skeleton; duplicate reference ignored"));
      return;
    }
    if (!sk_.parents.empty())
      doc_.fail(node, "second skeleton root (the first is '" + sk_.source_joint_names[0] +
                          "'); a humanoid has one root");
    read_joint(target, -1);
  }

  std::int32_t joint_index_of(pugi::xml_node joint) const {
    const auto it = joint_index_.find(joint.internal_object());
    return it == joint_index_.end() ? -1 : it->second;
  }

  // The H-Anim joint name a DEF ends in, at an underscore boundary ("hanim_l_hip", "Joe_HumanoidRoot"); the
  // longest such suffix wins, so "hanim_humanoid_root" gives humanoid_root and not a shorter tail.
  static std::string hanim_name_in_def(std::string_view def) {
    for (std::size_t p = 0; p < def.size(); ++p)
      if ((p == 0 || def[p - 1] == '_') && is_hanim_joint_name(def.substr(p))) return std::string(def.substr(p));
    return {};
  }

  void read_joint(pugi::xml_node node, std::int32_t parent) {
    std::string name = node.attribute("name").value();
    if (name.empty()) {
      const std::string_view def = node.attribute("DEF").value();
      if (def.empty()) doc_.fail(node, "joint without name or DEF");
      name = hanim_name_in_def(def);
      if (name.empty())
        doc_.fail(node, "joint without name, and its DEF '" + std::string(def) +
                            "' does not end in an H-Anim joint name; add name='...'");
      if (const auto it = name_line_.find(name); it != name_line_.end())
        doc_.fail(node, "joint without name: its DEF '" + std::string(def) + "' reads as '" + name +
                            "', which the joint at line " + std::to_string(it->second) + " already has");
      sk_.warnings.push_back(doc_.warning(node, "joint without name; named '" + name + "' after its DEF"));
    }
    if (const auto it = name_line_.find(name); it != name_line_.end())
      doc_.fail(node, "duplicate joint name '" + name + "' (first at line " + std::to_string(it->second) + ")");
    name_line_.emplace(name, doc_.line_of(node));

    std::optional<glm::vec3> center = xml::vec3_attr(doc_, node, "center");
    if (!center) {
      // X3D's default centre is the origin, which for a real joint is always an omission rather than intent.
      // StandardHumanoid.x3d omits it on l/r_tarsal_interphalangeal_1 (toe tips): such a child takes its parent's
      // centre (a zero-length bone) with a warning, so the file loads; a root has nothing to inherit and fails.
      if (parent < 0) doc_.fail(node, "missing center");
      center = sk_.centers[static_cast<std::size_t>(parent)];
      sk_.warnings.push_back(doc_.warning(node, "missing center; using the parent's"));
    }

    JointLimits limits;
    const auto lower = xml::fixed_floats_attr(doc_, node, "llimit", 3);
    const auto upper = xml::fixed_floats_attr(doc_, node, "ulimit", 3);
    // X3D's empty llimit/ulimit means "no limit"; a file giving only one side keeps the other at a half turn.
    if (lower && !lower->empty()) limits.lower = glm::vec3((*lower)[0], (*lower)[1], (*lower)[2]) * radians_per_unit_;
    if (upper && !upper->empty()) limits.upper = glm::vec3((*upper)[0], (*upper)[1], (*upper)[2]) * radians_per_unit_;
    limits.present = (lower && !lower->empty()) || (upper && !upper->empty());
    check_limits(doc_, node, limits);

    glm::vec3 stiffness(1.0f);
    if (const auto s = xml::vec3_attr(doc_, node, "stiffness")) stiffness = *s;

    if (const auto t = xml::vec3_attr(doc_, node, "translation"); t && *t != glm::vec3(0.0f))
      sk_.warnings.push_back(doc_.warning(node, "non-zero translation ignored (rest pose is identity)"));
    if (const auto r = xml::fixed_floats_attr(doc_, node, "rotation", 4); r && (*r)[3] != 0.0f)
      sk_.warnings.push_back(doc_.warning(node, "non-zero rotation ignored (rest pose is identity)"));

    const auto index = static_cast<std::int32_t>(sk_.parents.size());
    sk_.source_joint_names.push_back(name);
    sk_.parents.push_back(parent);
    sk_.centers.push_back(*center);
    sk_.limits.push_back(limits);
    sk_.stiffness.push_back(stiffness);
    joint_index_.emplace(node.internal_object(), index);
    if (const pugi::xml_attribute def = node.attribute("DEF")) joint_by_def_.emplace(def.value(), index);

    RawSkin skin;
    skin.node = node;
    if (auto idx = xml::int_list_attr(doc_, node, "skinCoordIndex")) skin.indices = std::move(*idx);
    skin.weights = xml::float_list_attr(doc_, node, "skinCoordWeight");
    if (!skin.indices.empty() || skin.weights) any_skin_weights_ = true;
    raw_skin_.push_back(std::move(skin));

    on_path_.insert(node.internal_object());
    read_children(node, index);
    on_path_.erase(node.internal_object());
  }

  // Walks what a joint contains. Joints, Segments and Sites may sit directly inside or inside grouping nodes
  // (Transform, Group); everything else (marker Shapes, TouchSensors, ...) is ignored.
  void read_children(pugi::xml_node container, std::int32_t joint) {
    for (pugi::xml_node child : container.children()) {
      if (child.type() != pugi::node_element) continue;
      if (is_tag(child, "HAnimJoint")) {
        const pugi::xml_node target = resolve(child);
        if (on_path_.count(target.internal_object()) != 0)
          doc_.fail(child, "cycle: joint '" + std::string(target.attribute("name").value()) +
                               "' contains itself through USE");
        if (joint_index_of(target) >= 0) {
          sk_.warnings.push_back(doc_.warning(child, "joint is already in the skeleton; duplicate reference ignored"));
          continue;
        }
        read_joint(target, joint);
      } else if (is_tag(child, "HAnimSegment")) {
        if (child.attribute("USE")) continue;  // the DEF occurrence is the record
        add_segment(child, joint);
        read_segment_geometry(child, joint, glm::mat4(1.0f));
        read_children(child, joint);
      } else if (is_tag(child, "HAnimSite")) {
        if (!child.attribute("USE")) add_site(child, joint);
      } else if (!child.attribute("USE")) {
        read_children(child, joint);
      }
    }
  }

  void add_segment(pugi::xml_node node, std::int32_t joint) {
    SkeletonSegment segment;
    segment.name = node.attribute("name").value();
    if (segment.name.empty()) segment.name = node.attribute("DEF").value();
    segment.joint = joint;
    segment.mass = xml::float_attr(doc_, node, "mass").value_or(0.0f);
    segment.center_of_mass = xml::vec3_attr(doc_, node, "centerOfMass").value_or(glm::vec3(0.0f));
    sk_.segments.push_back(std::move(segment));
  }

  void add_site(pugi::xml_node node, std::int32_t joint) {
    SkeletonSite site;
    site.name = node.attribute("name").value();
    if (site.name.empty()) site.name = node.attribute("DEF").value();
    if (site.name.empty()) doc_.fail(node, "site without name or DEF");
    site.joint = joint;
    site.position = xml::vec3_attr(doc_, node, "translation").value_or(glm::vec3(0.0f));
    sk_.sites.push_back(std::move(site));
  }

  // ---- the humanoid's transform and the length unit -----------------------------------------------------------
  glm::quat axis_angle_attr(pugi::xml_node node, const char* attr) const {
    const auto r = xml::fixed_floats_attr(doc_, node, attr, 4);
    if (!r) return glm::quat(1, 0, 0, 0);
    const glm::vec3 axis((*r)[0], (*r)[1], (*r)[2]);
    const float length = glm::length(axis);
    if (!(length > 1e-12f)) return glm::quat(1, 0, 0, 0);  // X3D players read a zero axis as no rotation
    return glm::angleAxis((*r)[3] * radians_per_unit_, axis / length);
  }

  void apply_humanoid_transform() {
    const glm::vec3 scale = xml::vec3_attr(doc_, humanoid_, "scale").value_or(glm::vec3(1.0f));
    const glm::quat rotation = axis_angle_attr(humanoid_, "rotation");
    if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
      doc_.fail(humanoid_, "scale has a zero component; the figure would collapse");

    // The humanoid's own Transform (the same X3D semantics as a Transform around segment geometry), then the unit
    // to metres on top: P' = f (A P + b).
    const glm::mat4 m = transform_matrix(humanoid_);
    const glm::mat3 linear = metres_per_unit_ * glm::mat3(m);
    const glm::vec3 offset = metres_per_unit_ * glm::vec3(m[3]);
    const bool identity = linear == glm::mat3(1.0f) && offset == glm::vec3(0.0f);
    if (identity) return;
    auto place = [&](glm::vec3 p) { return linear * p + offset; };

    for (glm::vec3& c : sk_.centers) c = place(c);
    for (SkeletonSite& site : sk_.sites) site.position = place(site.position);
    for (SkeletonSegment& segment : sk_.segments) segment.center_of_mass = place(segment.center_of_mass);
    for (glm::vec3& p : sk_.skin_points) p = place(p);
    // A mirroring scale turns every triangle inside out; swapping two corners keeps the normals outward.
    if (glm::determinant(linear) < 0.0f)
      for (std::size_t t = 0; t + 2 < sk_.skin_triangles.size(); t += 3)
        std::swap(sk_.skin_triangles[t + 1], sk_.skin_triangles[t + 2]);

    // A joint's animated translation is an offset in its parent's frame, which at rest is the humanoid's: it takes
    // the linear part only. A rotation key q in the file's frame is R q R^-1 in ours (exact when the scale is
    // uniform: then the scale commutes with every rotation).
    const bool uniform = scale.x == scale.y && scale.y == scale.z;
    bool animated_rotation = false;
    for (AnimationClip& clip : asset_.clips) {
      for (TranslationTrack& track : clip.translations)
        for (glm::vec3& v : track.values) v = linear * v;
      for (RotationTrack& track : clip.rotations) {
        animated_rotation = true;
        for (glm::quat& q : track.values) q = glm::normalize(rotation * q * glm::conjugate(rotation));
      }
    }
    if (!uniform && animated_rotation)
      sk_.warnings.push_back(doc_.warning(humanoid_, "non-uniform scale: joint rotations of the clips are kept as "
                                                     "written, so limbs may shear as they turn"));
    if (rotation != glm::quat(1, 0, 0, 0) &&
        std::any_of(sk_.limits.begin(), sk_.limits.end(), [](const JointLimits& l) { return l.present; }))
      sk_.warnings.push_back(doc_.warning(humanoid_, "rotated humanoid: joint limits stay about the file's own "
                                                     "axes"));
  }

  // ---- segment geometry -----------------------------------------------------------------------------------------
  struct SegmentMesh {
    std::int32_t joint = -1;
    std::vector<glm::vec3> points;
    std::vector<std::uint32_t> triangles;
  };

  // X3D Transform: T(translation) T(center) R(rotation) R(scaleOrientation) S(scale) R(-scaleOrientation) T(-center).
  glm::mat4 transform_matrix(pugi::xml_node node) const {
    const glm::vec3 t = xml::vec3_attr(doc_, node, "translation").value_or(glm::vec3(0.0f));
    const glm::vec3 c = xml::vec3_attr(doc_, node, "center").value_or(glm::vec3(0.0f));
    const glm::vec3 sc = xml::vec3_attr(doc_, node, "scale").value_or(glm::vec3(1.0f));
    const glm::mat4 r = glm::mat4_cast(axis_angle_attr(node, "rotation"));
    const glm::mat4 so = glm::mat4_cast(axis_angle_attr(node, "scaleOrientation"));
    return glm::translate(glm::mat4(1.0f), t + c) * r * so * glm::scale(glm::mat4(1.0f), sc) * glm::transpose(so) *
           glm::translate(glm::mat4(1.0f), -c);
  }

  // Shapes under a segment, through Transforms and Groups; not into nested joints, segments or sites (they are
  // read as their own records).
  void read_segment_geometry(pugi::xml_node container, std::int32_t joint, const glm::mat4& to_humanoid) {
    for (pugi::xml_node child : container.children()) {
      if (child.type() != pugi::node_element) continue;
      const pugi::xml_node node = resolve(child);
      if (is_tag(node, "HAnimJoint") || is_tag(node, "HAnimSegment") || is_tag(node, "HAnimSite")) continue;
      if (is_tag(node, "Transform")) {
        read_segment_geometry(node, joint, to_humanoid * transform_matrix(node));
      } else if (is_tag(node, "Group") || is_tag(node, "StaticGroup") || is_tag(node, "Collision")) {
        read_segment_geometry(node, joint, to_humanoid);
      } else if (is_tag(node, "Shape")) {
        for (pugi::xml_node g : node.children()) {
          if (g.type() != pugi::node_element) continue;
          const pugi::xml_node geometry = resolve(g);
          if (is_tag(geometry, "IndexedFaceSet") || is_tag(geometry, "IndexedTriangleSet"))
            add_segment_mesh(geometry, joint, to_humanoid);
          else if (!is_tag(geometry, "Appearance"))
            skipped_segment_geometry_ = true;
        }
      }
    }
  }

  void add_segment_mesh(pugi::xml_node geometry, std::int32_t joint, const glm::mat4& to_humanoid) {
    const pugi::xml_node coordinate = find_descendant(geometry, "Coordinate");
    if (!coordinate) doc_.fail(geometry, "segment geometry without a Coordinate");
    SegmentMesh mesh;
    mesh.joint = joint;
    for (const glm::vec3& p : read_points(coordinate)) mesh.points.push_back(glm::vec3(to_humanoid * glm::vec4(p, 1.0f)));
    const std::size_t count = mesh.points.size();
    const bool fan_faces = is_tag(geometry, "IndexedFaceSet");
    const auto index = xml::int_list_attr(doc_, geometry, fan_faces ? "coordIndex" : "index")
                           .value_or(std::vector<std::int64_t>{});
    // X3D's ccw='false' winds the faces clockwise; the engine's triangles are counter-clockwise from outside. A
    // mirroring Transform turns them inside out as well.
    const bool flip = !xml::bool_attr(doc_, geometry, "ccw").value_or(true) != (glm::determinant(glm::mat3(to_humanoid)) < 0.0f);
    std::vector<std::uint32_t> polygon;
    auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      mesh.triangles.insert(mesh.triangles.end(), {a, flip ? c : b, flip ? b : c});
    };
    auto flush = [&] {
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) emit(polygon[0], polygon[k], polygon[k + 1]);
      polygon.clear();
    };
    for (const std::int64_t i : index) {
      if (fan_faces && i == -1) {
        flush();
        continue;
      }
      if (i < 0 || static_cast<std::size_t>(i) >= count)
        doc_.fail(geometry, std::string(fan_faces ? "coordIndex " : "index ") + std::to_string(i) +
                                " out of range (the segment mesh has " + std::to_string(count) + " points)");
      polygon.push_back(static_cast<std::uint32_t>(i));
      if (!fan_faces && polygon.size() == 3) flush();  // IndexedTriangleSet: every three indices are a triangle
    }
    if (fan_faces) flush();
    if (!fan_faces && !polygon.empty())
      doc_.fail(geometry, "index has " + std::to_string(index.size()) + " entries, not a multiple of 3");
    if (!mesh.triangles.empty()) segment_meshes_.push_back(std::move(mesh));
  }

  // The segments' meshes as the skin of a file that has none: every vertex weighted 1 to its segment's joint.
  void segments_as_skin() {
    if (segment_meshes_.empty()) return;
    if (!sk_.skin_points.empty()) {
      sk_.warnings.push_back(doc_.warning(humanoid_, "segment geometry ignored: the humanoid has a skin"));
      return;
    }
    std::vector<std::vector<std::uint32_t>> vertices_of(sk_.joint_count());
    for (const SegmentMesh& mesh : segment_meshes_) {
      const auto base = static_cast<std::uint32_t>(sk_.skin_points.size());
      for (std::size_t v = 0; v < mesh.points.size(); ++v) {
        vertices_of[static_cast<std::size_t>(mesh.joint)].push_back(base + static_cast<std::uint32_t>(v));
        sk_.skin_points.push_back(mesh.points[v]);
      }
      for (const std::uint32_t t : mesh.triangles) sk_.skin_triangles.push_back(base + t);
    }
    sk_.skin_offsets.assign(sk_.joint_count() + 1, 0);
    sk_.skin_influences.clear();
    for (std::size_t j = 0; j < sk_.joint_count(); ++j) {
      sk_.skin_offsets[j] = static_cast<std::uint32_t>(sk_.skin_influences.size());
      for (const std::uint32_t v : vertices_of[j]) sk_.skin_influences.push_back({v, 1.0f});
    }
    sk_.skin_offsets.back() = static_cast<std::uint32_t>(sk_.skin_influences.size());
    if (skipped_segment_geometry_)
      sk_.warnings.push_back(doc_.warning(humanoid_, "segment geometry other than IndexedFaceSet and "
                                                     "IndexedTriangleSet (lines, primitives) is not drawn"));
  }

  // ---- skin ------------------------------------------------------------------------------------------------
  std::vector<glm::vec3> read_points(pugi::xml_node coordinate) {
    const std::vector<float> v = xml::float_list_attr(doc_, coordinate, "point").value_or(std::vector<float>{});
    if (v.size() % 3 != 0)
      doc_.fail(coordinate, "point has " + std::to_string(v.size()) + " numbers, not a multiple of 3");
    std::vector<glm::vec3> points(v.size() / 3);
    for (std::size_t i = 0; i < points.size(); ++i) points[i] = glm::vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
    return points;
  }

  pugi::xml_node find_descendant(pugi::xml_node node, std::string_view tag) const {
    for (pugi::xml_node child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      const pugi::xml_node c = resolve(child);
      if (is_tag(c, tag)) return c;
      // Not into other USEs: <Group DEF='G'><Group USE='G'/></Group> is legal XML and would recurse forever.
      if (c != child) continue;
      if (const pugi::xml_node found = find_descendant(c, tag)) return found;
    }
    return {};
  }

  void read_skin() {
    pugi::xml_node faces;
    if (skin_node_) {
      const pugi::xml_node skin = resolve(skin_node_);
      faces = is_tag(skin, "IndexedFaceSet") ? skin : find_descendant(skin, "IndexedFaceSet");
      if (!faces) sk_.warnings.push_back(doc_.warning(skin_node_, "skin has no IndexedFaceSet; no triangles"));
    }
    pugi::xml_node coordinate = skin_coord_;
    if (!coordinate && faces) coordinate = find_descendant(faces, "Coordinate");
    const bool have_points = static_cast<bool>(coordinate);
    if (coordinate) sk_.skin_points = read_points(coordinate);
    const std::size_t point_count = sk_.skin_points.size();

    if (faces) {
      const auto index = xml::int_list_attr(doc_, faces, "coordIndex").value_or(std::vector<std::int64_t>{});
      // Polygons end at -1 (the last one may omit it) and become triangle fans around their first vertex.
      std::vector<std::uint32_t> polygon;
      auto flush = [&] {
        for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
          sk_.skin_triangles.push_back(polygon[0]);
          sk_.skin_triangles.push_back(polygon[k]);
          sk_.skin_triangles.push_back(polygon[k + 1]);
        }
        polygon.clear();
      };
      for (const std::int64_t i : index) {
        if (i == -1) {
          flush();
          continue;
        }
        if (i < 0 || static_cast<std::size_t>(i) >= point_count)
          doc_.fail(faces, "coordIndex " + std::to_string(i) + " out of range (skin has " +
                               std::to_string(point_count) + " points)");
        polygon.push_back(static_cast<std::uint32_t>(i));
      }
      flush();
    }

    if (!any_skin_weights_) return;
    // Weights policy:
    // * skinCoordIndex and skinCoordWeight of different lengths (Joe's l_elbow: 12 vs 15) are paired up to the
    //   shorter list and the rest is dropped, with a warning naming the joint. Rejecting the file instead would
    //   lose the only weighted sample we have for a defect that is harmless in practice (Joe's extras are 1s).
    // * skinCoordIndex without skinCoordWeight means weight 1 for every listed vertex (a rigid binding), which
    //   is what a lone index list plainly intends.
    sk_.skin_offsets.assign(sk_.joint_count() + 1, 0);
    for (std::size_t j = 0; j < raw_skin_.size(); ++j) {
      const RawSkin& raw = raw_skin_[j];
      sk_.skin_offsets[j] = static_cast<std::uint32_t>(sk_.skin_influences.size());
      std::size_t n = raw.indices.size();
      if (raw.weights && raw.weights->size() != raw.indices.size()) {
        n = std::min(n, raw.weights->size());
        sk_.warnings.push_back(doc_.warning(
            raw.node, "skinCoordIndex has " + std::to_string(raw.indices.size()) + " entries but skinCoordWeight has " +
                          std::to_string(raw.weights->size()) + "; paired the first " + std::to_string(n)));
      }
      for (std::size_t k = 0; k < n; ++k) {
        const std::int64_t v = raw.indices[k];
        if (v < 0 || (have_points && static_cast<std::size_t>(v) >= point_count))
          doc_.fail(raw.node, "skinCoordIndex " + std::to_string(v) + " out of range (skin has " +
                                  std::to_string(point_count) + " points)");
        sk_.skin_influences.push_back({static_cast<std::uint32_t>(v), raw.weights ? (*raw.weights)[k] : 1.0f});
      }
    }
    sk_.skin_offsets.back() = static_cast<std::uint32_t>(sk_.skin_influences.size());
  }

  // ---- animation -----------------------------------------------------------------------------------------
  const ParsedInterpolator& parse_interpolator(pugi::xml_node node, float cycle) {
    // Keyed by node and cycle: the same interpolator could in principle be driven by two clocks.
    const auto key = std::make_pair(node.internal_object(), cycle);
    if (const auto it = parsed_.find(key); it != parsed_.end()) return it->second;

    const bool rotation = is_tag(node, "OrientationInterpolator");
    const std::size_t width = rotation ? 4 : 3;
    const std::vector<float> keys = xml::float_list_attr(doc_, node, "key").value_or(std::vector<float>{});
    const std::vector<float> values = xml::float_list_attr(doc_, node, "keyValue").value_or(std::vector<float>{});
    if (keys.empty()) doc_.fail(node, "no keys");
    if (values.size() % width != 0 || values.size() / width != keys.size())
      doc_.fail(node, "key has " + std::to_string(keys.size()) + " entries but keyValue has " +
                          std::to_string(values.size()) + " numbers, expected " +
                          std::to_string(keys.size() * width));

    ParsedInterpolator out;
    for (std::size_t k = 0; k < keys.size(); ++k) {
      if (keys[k] < 0.0f || keys[k] > 1.0f)
        doc_.fail(node, "key " + std::to_string(keys[k]) + " outside the fraction range [0, 1]");
      if (k > 0 && keys[k] < keys[k - 1]) doc_.fail(node, "keys decrease at entry " + std::to_string(k));
      const float* v = values.data() + k * width;
      if (k > 0 && keys[k] == keys[k - 1]) {
        // X3D allows a repeated key (a jump); AnimationClip wants strictly increasing times, so the later value
        // replaces the earlier one. Nudging the time by an epsilon was the alternative; it keeps the jump but
        // plants a near-zero-length segment in every sampler. No real file we have does this.
        sk_.warnings.push_back(doc_.warning(node, "repeated key " + std::to_string(keys[k]) + "; kept the later value"));
        out.times.pop_back();
        if (rotation)
          out.rotations.pop_back();
        else
          out.positions.pop_back();
      }
      out.times.push_back(keys[k] * cycle);
      if (rotation) {
        const glm::vec3 axis(v[0], v[1], v[2]);
        const float length = glm::length(axis);
        // A zero axis has no direction to turn about: X3D players treat it as no rotation.
        out.rotations.push_back(length > 1e-12f ? glm::angleAxis(v[3] * radians_per_unit_, axis / length)
                                                : glm::quat(1, 0, 0, 0));
      } else {
        out.positions.emplace_back(v[0], v[1], v[2]);
      }
    }
    return parsed_.emplace(key, std::move(out)).first->second;
  }

  void read_animation() {
    // fraction routes: interpolator DEF -> clocks; value routes: interpolator DEF -> (joint, field) targets.
    std::map<std::string, std::vector<std::string>> clock_targets;  // clock DEF -> interpolator DEFs, route order
    struct Target {
      pugi::xml_node route;
      std::int32_t joint;
      bool rotation;
    };
    std::map<std::string, std::vector<Target>> value_targets;
    for (pugi::xml_node route : routes_) {
      const std::string from = route.attribute("fromNode").value();
      const std::string to = route.attribute("toNode").value();
      const std::string_view from_field = route.attribute("fromField").value();
      const std::string_view to_field = route.attribute("toField").value();
      for (const std::string* node_name : {&from, &to})
        if (defs_.find(*node_name) == defs_.end())
          doc_.fail(route, "ROUTE names unknown node '" + *node_name + "'");
      const pugi::xml_node from_node = defs_.at(from);
      const pugi::xml_node to_node = defs_.at(to);
      const bool to_interpolator = is_tag(to_node, "OrientationInterpolator") || is_tag(to_node, "PositionInterpolator");
      if (is_tag(from_node, "TimeSensor") && from_field == "fraction_changed" && to_interpolator &&
          (to_field == "set_fraction" || to_field == "fraction")) {
        clock_targets[from].push_back(to);
      } else if (is_tag(to_node, "HAnimJoint") && from_field == "value_changed") {
        const auto joint = joint_by_def_.find(to);
        if (joint == joint_by_def_.end()) continue;  // a joint of another humanoid
        const bool to_rotation = to_field == "set_rotation" || to_field == "rotation";
        const bool to_translation = to_field == "set_translation" || to_field == "translation";
        if ((to_rotation && !is_tag(from_node, "OrientationInterpolator")) ||
            (to_translation && !is_tag(from_node, "PositionInterpolator")) || (!to_rotation && !to_translation)) {
          sk_.warnings.push_back(doc_.warning(route, "ROUTE " + from + "." + std::string(from_field) + " -> " + to +
                                                         "." + std::string(to_field) + " not understood; ignored"));
          continue;
        }
        value_targets[from].push_back({route, joint->second, to_rotation});
      }
    }

    for (pugi::xml_node clock : time_sensors_) {
      const std::string name = clock.attribute("DEF").value();
      const auto driven = clock_targets.find(name);
      if (name.empty() || driven == clock_targets.end()) continue;
      AnimationClip clip;
      clip.name = name;
      clip.duration = xml::float_attr(doc_, clock, "cycleInterval").value_or(1.0f);
      if (!(clip.duration > 0.0f)) doc_.fail(clock, "cycleInterval must be positive");
      // X3D's TimeSensor default is loop='false' (play once); follow the file rather than AnimationClip's default.
      clip.loop = xml::bool_attr(doc_, clock, "loop").value_or(false);
      std::unordered_set<std::int64_t> seen;  // joint * 2 + (rotation ? 0 : 1)
      for (const std::string& interpolator : driven->second) {
        const auto targets = value_targets.find(interpolator);
        if (targets == value_targets.end()) continue;  // drives nothing of this humanoid
        const pugi::xml_node node = defs_.at(interpolator);
        const ParsedInterpolator& keys = parse_interpolator(node, clip.duration);
        for (const Target& t : targets->second) {
          if (!seen.insert(std::int64_t{t.joint} * 2 + (t.rotation ? 0 : 1)).second) {
            sk_.warnings.push_back(doc_.warning(t.route, "joint '" + sk_.source_joint_names[t.joint] +
                                                             "' already animated by clock '" + name +
                                                             "'; this ROUTE is ignored"));
            continue;
          }
          if (t.rotation)
            clip.rotations.push_back({t.joint, keys.times, keys.rotations});
          else
            clip.translations.push_back({t.joint, keys.times, keys.positions});
        }
      }
      if (clip.channel_count() > 0) asset_.clips.push_back(std::move(clip));
    }
    std::stable_sort(asset_.clips.begin(), asset_.clips.end(), [](const AnimationClip& a, const AnimationClip& b) {
      return a.channel_count() > b.channel_count();
    });
  }

  const xml::Document& doc_;
  HumanoidAsset asset_;
  Skeleton& sk_;

  std::unordered_map<std::string, pugi::xml_node> defs_;
  std::vector<pugi::xml_node> humanoids_;
  std::vector<pugi::xml_node> time_sensors_;
  std::vector<pugi::xml_node> routes_;

  pugi::xml_node humanoid_;
  std::unordered_map<const void*, std::int32_t> joint_index_;  // element -> joint index
  std::unordered_map<std::string, std::int32_t> joint_by_def_;
  std::unordered_map<std::string, int> name_line_;
  std::unordered_set<const void*> on_path_;  // joints on the current root-to-node path (cycle detection)
  std::vector<RawSkin> raw_skin_;
  bool any_skin_weights_ = false;
  pugi::xml_node skin_node_;
  pugi::xml_node skin_coord_;
  std::vector<SegmentMesh> segment_meshes_;
  bool skipped_segment_geometry_ = false;
  float metres_per_unit_ = 1.0f;   // X3D UNIT length conversionFactor
  float radians_per_unit_ = 1.0f;  // X3D UNIT angle conversionFactor
  std::map<std::pair<const void*, float>, ParsedInterpolator> parsed_;
};

}  // namespace

HumanoidAsset read_x3d_humanoid(const xml::Document& doc) { return X3dReader(doc).read(); }

}  // namespace strata::detail
