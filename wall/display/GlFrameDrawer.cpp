#include "wall/display/GlFrameDrawer.h"

// Types and enums only: without GL_GLEXT_PROTOTYPES this declares no gl* function, so nothing
// here can call GL except through the table below.
#include <GL/glcorearb.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <string>

#include "base/Error.h"

namespace wall {
namespace {

#define WALL_GL_FUNCTIONS(X)                           \
  X(PFNGLGETSTRINGPROC, glGetString)                   \
  X(PFNGLGETERRORPROC, glGetError)                     \
  X(PFNGLCREATESHADERPROC, glCreateShader)             \
  X(PFNGLSHADERSOURCEPROC, glShaderSource)             \
  X(PFNGLCOMPILESHADERPROC, glCompileShader)           \
  X(PFNGLGETSHADERIVPROC, glGetShaderiv)               \
  X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)     \
  X(PFNGLDELETESHADERPROC, glDeleteShader)             \
  X(PFNGLCREATEPROGRAMPROC, glCreateProgram)           \
  X(PFNGLATTACHSHADERPROC, glAttachShader)             \
  X(PFNGLLINKPROGRAMPROC, glLinkProgram)               \
  X(PFNGLGETPROGRAMIVPROC, glGetProgramiv)             \
  X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)   \
  X(PFNGLDELETEPROGRAMPROC, glDeleteProgram)           \
  X(PFNGLUSEPROGRAMPROC, glUseProgram)                 \
  X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation) \
  X(PFNGLUNIFORM1IPROC, glUniform1i)                   \
  X(PFNGLUNIFORM2IPROC, glUniform2i)                   \
  X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays)       \
  X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)       \
  X(PFNGLDELETEVERTEXARRAYSPROC, glDeleteVertexArrays) \
  X(PFNGLGENTEXTURESPROC, glGenTextures)               \
  X(PFNGLBINDTEXTUREPROC, glBindTexture)               \
  X(PFNGLACTIVETEXTUREPROC, glActiveTexture)           \
  X(PFNGLTEXIMAGE2DPROC, glTexImage2D)                 \
  X(PFNGLTEXSUBIMAGE2DPROC, glTexSubImage2D)           \
  X(PFNGLTEXPARAMETERIPROC, glTexParameteri)           \
  X(PFNGLDELETETEXTURESPROC, glDeleteTextures)         \
  X(PFNGLPIXELSTOREIPROC, glPixelStorei)               \
  X(PFNGLVIEWPORTPROC, glViewport)                     \
  X(PFNGLDISABLEPROC, glDisable)                       \
  X(PFNGLCLEARCOLORPROC, glClearColor)                 \
  X(PFNGLCLEARPROC, glClear)                           \
  X(PFNGLDRAWARRAYSPROC, glDrawArrays)                 \
  X(PFNGLREADBUFFERPROC, glReadBuffer)                 \
  X(PFNGLREADPIXELSPROC, glReadPixels)                 \
  X(PFNGLFINISHPROC, glFinish)

// The GL functions we use, named as GL names them: `gl.glViewport(...)`.
struct GlFunctions {
#define WALL_GL_DECLARE(type, name) type name = nullptr;
  WALL_GL_FUNCTIONS(WALL_GL_DECLARE)
#undef WALL_GL_DECLARE
};

GlFunctions loadFunctions(GlProcLoader loader) {
  GlFunctions gl;
  std::string missing;
#define WALL_GL_LOAD(type, name)                   \
  gl.name = reinterpret_cast<type>(loader(#name)); \
  if (!gl.name) missing += std::string(missing.empty() ? "" : ", ") + #name;
  WALL_GL_FUNCTIONS(WALL_GL_LOAD)
#undef WALL_GL_LOAD
  if (!missing.empty())
    throw base::Error("OpenGL functions not found through the loader: " + missing);
  return gl;
}

// A triangle covering the viewport, from gl_VertexID alone (core profile: a VAO, no buffers).
constexpr const char* kVertexShader = R"(#version 330 core
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

// Window pixel → texel, 1:1. Texture row 0 is the frame's top row; GL's window row 0 is the
// bottom, hence the flip. texelFetch: no filtering, so no off-by-one at texel edges.
constexpr const char* kFragmentShader = R"(#version 330 core
uniform sampler2D frame;
uniform ivec2 origin;  // window coordinates of the viewport's bottom-left
uniform int frameHeight;
out vec4 color;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy) - origin;
  color = texelFetch(frame, ivec2(p.x, frameHeight - 1 - p.y), 0);
}
)";

}  // namespace

struct GlFrameDrawer::Impl {
  GlFunctions gl;
  GLuint program = 0, vao = 0, texture = 0;
  GLint originLocation = -1, heightLocation = -1;
  int textureWidth = 0, textureHeight = 0;

  void check(const char* what) const {
    const GLenum e = gl.glGetError();
    if (e != GL_NO_ERROR) {
      char code[16];
      std::snprintf(code, sizeof code, "0x%04x", e);
      throw base::Error(std::string("OpenGL error ") + code + " in " + what);
    }
  }

  GLuint compile(GLenum kind, const char* source) const {
    const GLuint s = gl.glCreateShader(kind);
    gl.glShaderSource(s, 1, &source, nullptr);
    gl.glCompileShader(s);
    GLint ok = 0;
    gl.glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[2048] = "";
      gl.glGetShaderInfoLog(s, sizeof log, nullptr, log);
      gl.glDeleteShader(s);
      throw base::Error(std::string("the presenter's ") +
                        (kind == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                        " shader does not compile: " + log);
    }
    return s;
  }
};

GlFrameDrawer::GlFrameDrawer(GlProcLoader loader) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.gl = loadFunctions(loader);
  const GlFunctions& gl = m.gl;
  if (!gl.glGetString(GL_VERSION))
    throw base::Error("no current OpenGL context answers (glGetString(GL_VERSION) is null)");
  const GLuint vs = m.compile(GL_VERTEX_SHADER, kVertexShader);
  const GLuint fs = m.compile(GL_FRAGMENT_SHADER, kFragmentShader);
  m.program = gl.glCreateProgram();
  gl.glAttachShader(m.program, vs);
  gl.glAttachShader(m.program, fs);
  gl.glLinkProgram(m.program);
  gl.glDeleteShader(vs);
  gl.glDeleteShader(fs);
  GLint linked = 0;
  gl.glGetProgramiv(m.program, GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[2048] = "";
    gl.glGetProgramInfoLog(m.program, sizeof log, nullptr, log);
    throw base::Error(std::string("the presenter's shader program does not link: ") + log);
  }
  m.originLocation = gl.glGetUniformLocation(m.program, "origin");
  m.heightLocation = gl.glGetUniformLocation(m.program, "frameHeight");
  gl.glUseProgram(m.program);
  gl.glUniform1i(gl.glGetUniformLocation(m.program, "frame"), 0);
  gl.glGenVertexArrays(1, &m.vao);
  gl.glGenTextures(1, &m.texture);
  gl.glActiveTexture(GL_TEXTURE0);
  gl.glBindTexture(GL_TEXTURE_2D, m.texture);
  // texelFetch ignores filtering, but an incomplete texture (mipmaps expected) samples black.
  gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl.glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  gl.glDisable(GL_BLEND);
  gl.glDisable(GL_DEPTH_TEST);
  m.check("setting up the presenter");
}

GlFrameDrawer::~GlFrameDrawer() {
  const GlFunctions& gl = impl_->gl;
  if (impl_->texture) gl.glDeleteTextures(1, &impl_->texture);
  if (impl_->vao) gl.glDeleteVertexArrays(1, &impl_->vao);
  if (impl_->program) gl.glDeleteProgram(impl_->program);
}

void GlFrameDrawer::resize(int width, int height) {
  Impl& m = *impl_;
  if (width == m.textureWidth && height == m.textureHeight) return;
  const GlFunctions& gl = m.gl;
  gl.glActiveTexture(GL_TEXTURE0);
  gl.glBindTexture(GL_TEXTURE_2D, m.texture);
  gl.glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  m.check("allocating the frame's texture");
  m.textureWidth = width;
  m.textureHeight = height;
}

void GlFrameDrawer::upload(const std::uint32_t* first, int stride, int x, int y, int w, int h) {
  Impl& m = *impl_;
  const GlFunctions& gl = m.gl;
  gl.glActiveTexture(GL_TEXTURE0);
  gl.glBindTexture(GL_TEXTURE_2D, m.texture);
  gl.glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl.glPixelStorei(GL_UNPACK_ROW_LENGTH, stride);
  // Bytes R, G, B, A in memory (wall/image/Image.h) are GL_RGBA + GL_UNSIGNED_BYTE.
  gl.glTexSubImage2D(GL_TEXTURE_2D, 0, x, y, w, h, GL_RGBA, GL_UNSIGNED_BYTE, first);
  gl.glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  m.check("uploading pixels");
}

void GlFrameDrawer::draw(int drawableWidth, int drawableHeight) {
  Impl& m = *impl_;
  const GlFunctions& gl = m.gl;
  const int width = m.textureWidth, height = m.textureHeight;
  gl.glActiveTexture(GL_TEXTURE0);
  gl.glBindTexture(GL_TEXTURE_2D, m.texture);
  gl.glViewport(0, 0, drawableWidth, drawableHeight);
  gl.glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  gl.glClear(GL_COLOR_BUFFER_BIT);
  // The frame's top-left at the drawable's top-left: GL counts rows from the bottom.
  const int y0 = drawableHeight - height;
  gl.glViewport(0, y0, width, height);
  gl.glUseProgram(m.program);
  gl.glUniform2i(m.originLocation, 0, y0);
  gl.glUniform1i(m.heightLocation, height);
  gl.glBindVertexArray(m.vao);
  gl.glDrawArrays(GL_TRIANGLES, 0, 3);
  m.check("drawing a frame");
}

void GlFrameDrawer::finish() { impl_->gl.glFinish(); }

Image GlFrameDrawer::read(int width, int height, int drawableHeight, bool frontBuffer) {
  const GlFunctions& gl = impl_->gl;
  if (frontBuffer) gl.glReadBuffer(GL_FRONT);
  gl.glPixelStorei(GL_PACK_ALIGNMENT, 4);
  gl.glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  Image bottomUp(width, height);
  gl.glReadPixels(0, drawableHeight - height, width, height, GL_RGBA, GL_UNSIGNED_BYTE,
                  bottomUp.pixels.data());
  impl_->check("reading pixels back");
  Image out(width, height);
  for (int y = 0; y < height; ++y)
    std::copy_n(&bottomUp.at(0, height - 1 - y), width, &out.at(0, y));
  return out;
}

std::string GlFrameDrawer::version() const {
  const auto* s = reinterpret_cast<const char*>(impl_->gl.glGetString(GL_VERSION));
  return s ? s : "";
}

std::string GlFrameDrawer::renderer() const {
  const auto* s = reinterpret_cast<const char*>(impl_->gl.glGetString(GL_RENDERER));
  return s ? s : "";
}

}  // namespace wall
