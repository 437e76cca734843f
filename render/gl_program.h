#pragma once
// GL helpers the render passes share: an owning handle for GL object names and shader programs built from the
// GLSL files under render/shaders/, which the build embeds into the library (CMakeLists.txt STRATA_EMBEDDED_FILES),
// so a program needs no file beside it at run time. Every compile or link error names the shader file.
//
// The header is GL-free (names are `unsigned`, which GLuint is): the pass headers include it and are installed
// with the library, and a consumer of the package should not need libepoxy's headers to include them.
#include <string_view>

namespace strata {

// What a GlObject holds, which decides how it is created and deleted.
enum class GlKind { kBuffer, kVertexArray, kFramebuffer, kRenderbuffer, kProgram, kTexture2D, kTexture2DArray, kTextureBuffer, kTexture2DMultisample };

// Owns one GL object name and deletes it with the matching glDelete*. Move-only. The GL context that created it
// must be current when it is destroyed (as for every pass). An owning handle rather than create/destroy pairs
// in each pass: a constructor that throws half-way (a shader that fails to link after buffers exist) then frees
// what it made without a hand-written destroy_all that must list every name.
class GlObject {
 public:
  GlObject() = default;
  // A new object of the kind: glCreate* (direct state access), glCreateProgram for an empty program (link_program
  // below makes complete ones).
  explicit GlObject(GlKind kind);
  ~GlObject() { reset(); }
  GlObject(GlObject&& other) noexcept : kind_(other.kind_), name_(other.release()) {}
  GlObject& operator=(GlObject&& other) noexcept;
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;

  unsigned id() const { return name_; }
  explicit operator bool() const { return name_ != 0; }
  void reset();
  unsigned release() {
    const unsigned name = name_;
    name_ = 0;
    return name;
  }

 private:
  GlKind kind_ = GlKind::kBuffer;
  unsigned name_ = 0;
};

// The text of an embedded shader by its path from the source root, e.g. "render/shaders/body.vert". Throws
// std::runtime_error naming the path when the build did not embed it.
std::string_view shader_source(std::string_view path);

// Compiles and links a vertex + fragment program from the given sources; `vertex_name` and `fragment_name` are
// what errors call the two stages (their file paths). Throws std::runtime_error "<file>: failed to compile: <GL
// log>" or "<vertex file> + <fragment file>: failed to link: <GL log>".
GlObject link_program(std::string_view vertex_name, std::string_view vertex_source, std::string_view fragment_name,
                      std::string_view fragment_source);
// The same with both stages read from the embedded shader files.
GlObject link_program(std::string_view vertex_path, std::string_view fragment_path);

}  // namespace strata
