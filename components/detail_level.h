#pragma once
// DetailLevel: the resolution a crowd's bodies are drawn at, as a typed value defined once. Before it, levels
// were plain ints with magic numbers (10 + k for subdivision, 20 for auto) spread over nine files.
//
//   none      no body: skeletons only                                    name "-1"
//   mesh k    the body's level k, 0 finest (the paper's three levels)    names "0", "1", "2"
//   subdiv k  the low-resolution cage skinned, then Loop-refined k times "S1", "S2", "S3"
//   automatic each visible walker at a mesh level or as an impostor,     "auto"
//             chosen by its height on screen with hysteresis, the
//             nearest within a budget of meshes (systems/lod.h)
//   impostor  every visible walker an impostor: one textured quad from   "impostor"
//             the rig's baked atlas (render/impostor_atlas.h); for tests
//             and comparisons
//
// Adding a kind of level means one enumerator here, its name in name()/parse(), the table it lives in
// (DetailSlot, scene/crowd.h) and the system that fills that table's skinned storage (scene/step.cpp).
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>

namespace strata {

inline constexpr int kMaxMeshLevels = 3;   // the paper's three resolution levels
inline constexpr int kMaxSubdivDepth = 3;  // S1..S3; S4 would be ~460 k vertices per walker

class DetailLevel {
 public:
  enum class Kind : std::uint8_t { None, Mesh, Subdiv, Automatic, Impostor };

  constexpr DetailLevel() = default;  // mesh level 0
  static constexpr DetailLevel none() { return {Kind::None, 0}; }
  static constexpr DetailLevel mesh(int level) { return {Kind::Mesh, level}; }
  static constexpr DetailLevel subdiv(int depth) { return {Kind::Subdiv, depth}; }
  static constexpr DetailLevel automatic() { return {Kind::Automatic, 0}; }
  static constexpr DetailLevel impostor() { return {Kind::Impostor, 0}; }

  constexpr Kind kind() const { return kind_; }
  constexpr bool is_none() const { return kind_ == Kind::None; }
  constexpr bool is_mesh() const { return kind_ == Kind::Mesh; }
  constexpr bool is_subdiv() const { return kind_ == Kind::Subdiv; }
  constexpr bool is_automatic() const { return kind_ == Kind::Automatic; }
  constexpr bool is_impostor() const { return kind_ == Kind::Impostor; }
  // The mesh level (is_mesh) or the subdivision depth (is_subdiv); 0 otherwise.
  constexpr int index() const { return index_; }

  // "-1", "0".."2", "S1".."S3", "auto", "impostor": what --level takes and the reports print.
  std::string name() const {
    switch (kind_) {
      case Kind::None: return "-1";
      case Kind::Mesh: return std::to_string(index_);
      case Kind::Automatic: return "auto";
      case Kind::Impostor: return "impostor";
      case Kind::Subdiv: break;
    }
    std::string name = "S";  // appended rather than "S" + std::string, which trips GCC 12's -Wrestrict false positive
    name += std::to_string(index_);
    return name;
  }
  // The inverse of name() (also lower-case "s1".."s3"); nullopt for anything else, e.g. "3" or "S4".
  static std::optional<DetailLevel> parse(std::string_view text) {
    if (text == "-1") return none();
    if (text == "auto") return automatic();
    if (text == "impostor") return impostor();
    if (text.size() == 1 && text[0] >= '0' && text[0] < '0' + kMaxMeshLevels) return mesh(text[0] - '0');
    if (text.size() == 2 && (text[0] == 'S' || text[0] == 's') && text[1] >= '1' && text[1] <= '0' + kMaxSubdivDepth)
      return subdiv(text[1] - '0');
    return std::nullopt;
  }
  // The number summary.json and the bench JSON have always carried for a level (0..2 meshes, 11..13 for S1..S3,
  // 20 for auto, -1 for none; 30 for impostor, added later): kept so those keys' values do not change.
  constexpr int json_code() const {
    switch (kind_) {
      case Kind::None: return -1;
      case Kind::Mesh: return index_;
      case Kind::Subdiv: return 10 + index_;
      case Kind::Automatic: return 20;
      case Kind::Impostor: return 30;
    }
    return -1;
  }

  friend constexpr bool operator==(DetailLevel, DetailLevel) = default;

 private:
  constexpr DetailLevel(Kind kind, int index) : kind_(kind), index_(static_cast<std::int8_t>(index)) {}
  Kind kind_ = Kind::Mesh;
  std::int8_t index_ = 0;
};

inline std::ostream& operator<<(std::ostream& out, DetailLevel level) { return out << level.name(); }

}  // namespace strata
