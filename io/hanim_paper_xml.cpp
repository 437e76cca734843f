// The paper-era simple XML (Memisoglu 2003, tech-brief.md section 2.7):
//   <Humanoid [name=".." author=".."]> [<author>..</author>] [<name>..</name>] [<center value="x y z"/>]
//     <Joint name=".." center="x y z" [limitx="lo hi"] [limity=".."] [limitz=".."]>
//       <Segment name=".." [mass=".."]/>  <Site name=".." center="x y z"/>  <Joint ..>..</Joint>
//     </Joint>
//   </Humanoid>
// Whether author/name were child elements or attributes is not known, so both are accepted (the child wins).
#include <unordered_map>

#include "io/hanim_readers.h"

namespace strata::detail {
namespace {

class PaperReader {
 public:
  explicit PaperReader(const xml::Document& doc) : doc_(doc) {}

  HumanoidAsset read() {
    const pugi::xml_node humanoid = doc_.root();
    Skeleton& sk = asset_.skeleton;
    asset_.format = HumanoidFormat::PaperXml;
    sk.source = doc_.source_name();
    sk.name = humanoid.attribute("name").value();
    if (const pugi::xml_node name = humanoid.child("name")) sk.name = name.text().get();
    // The humanoid-level centre is the root joint's position again; it is validated but not stored.
    if (const pugi::xml_node center = humanoid.child("center"); center && !xml::vec3_attr(doc_, center, "value"))
      doc_.fail(center, "missing value");

    pugi::xml_node root_joint;
    for (pugi::xml_node joint : humanoid.children("Joint")) {
      if (root_joint)
        doc_.fail(joint, "second root joint (the first is at line " + std::to_string(doc_.line_of(root_joint)) +
                             "); a humanoid has one root");
      root_joint = joint;
    }
    if (!root_joint) doc_.fail(humanoid, "no <Joint> found in the humanoid");
    read_joint(root_joint, -1);
    finalize_joint_names(sk);
    return std::move(asset_);
  }

 private:
  void read_joint(pugi::xml_node node, std::int32_t parent) {
    Skeleton& sk = asset_.skeleton;
    const std::string name = node.attribute("name").value();
    if (name.empty()) doc_.fail(node, "joint without name");
    if (const auto it = first_line_.find(name); it != first_line_.end())
      doc_.fail(node, "duplicate joint name '" + name + "' (first at line " + std::to_string(it->second) + ")");
    first_line_.emplace(name, doc_.line_of(node));

    const std::optional<glm::vec3> center = xml::vec3_attr(doc_, node, "center");
    if (!center) doc_.fail(node, "missing center");

    // Axes not given stay at JointLimits' defaults (a full turn either way, i.e. unlimited) but the joint still
    // counts as limited (present) as soon as one axis is.
    JointLimits limits;
    static constexpr const char* kAttrs[3] = {"limitx", "limity", "limitz"};
    for (int a = 0; a < 3; ++a) {
      if (const auto range = xml::fixed_floats_attr(doc_, node, kAttrs[a], 2)) {
        limits.lower[a] = (*range)[0];
        limits.upper[a] = (*range)[1];
        limits.present = true;
      }
    }
    check_limits(doc_, node, limits);

    const auto index = static_cast<std::int32_t>(sk.parents.size());
    sk.source_joint_names.push_back(name);
    sk.parents.push_back(parent);
    sk.centers.push_back(*center);
    sk.limits.push_back(limits);
    sk.stiffness.emplace_back(1.0f);

    for (pugi::xml_node child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      const std::string_view tag = child.name();
      if (tag == "Joint") {
        read_joint(child, index);
      } else if (tag == "Segment") {
        SkeletonSegment segment;
        segment.name = child.attribute("name").value();
        segment.joint = index;
        segment.mass = xml::float_attr(doc_, child, "mass").value_or(0.0f);
        sk.segments.push_back(std::move(segment));
      } else if (tag == "Site") {
        SkeletonSite site;
        site.name = child.attribute("name").value();
        if (site.name.empty()) doc_.fail(child, "site without name");
        site.joint = index;
        const std::optional<glm::vec3> position = xml::vec3_attr(doc_, child, "center");
        if (!position) doc_.fail(child, "missing center");
        site.position = *position;
        sk.sites.push_back(std::move(site));
      }
      // Anything else (comments aside) is not part of the DTD; ignored like X3D's unknown nodes.
    }
  }

  const xml::Document& doc_;
  HumanoidAsset asset_;
  std::unordered_map<std::string, int> first_line_;  // joint name -> line of its first definition
};

}  // namespace

HumanoidAsset read_paper_humanoid(const xml::Document& doc) { return PaperReader(doc).read(); }

}  // namespace strata::detail
