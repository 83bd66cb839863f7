// GL helpers shared by the offscreen renderer (renderer.cpp) and the scene drawer
// (scene_drawer.cpp). Internal to the walkthrough library: both load their GL entry points into a
// glad 2 "--mx" GladGLContext, which every function here takes explicitly.
#pragma once

#include <glad/gl.h>

#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace walkvis::gl_detail {

// Compiles and links a vertex and a fragment shader. Returns the program, or 0 with `error` set to
// the compiler's log (or "shader program did not link"); nothing is left allocated on failure.
inline GLuint buildProgram(GladGLContext& gl, const char* vertex_source, const char* fragment_source,
                           std::string& error) {
  auto compile = [&](GLenum type, const char* source) {
    GLuint s = gl.CreateShader(type);
    gl.ShaderSource(s, 1, &source, nullptr);
    gl.CompileShader(s);
    GLint ok = 0;
    gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char buf[1024] = {};
      gl.GetShaderInfoLog(s, sizeof buf, nullptr, buf);
      error += buf;
    }
    return s;
  };
  error.clear();
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex_source);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment_source);
  if (!error.empty()) {
    gl.DeleteShader(vs);
    gl.DeleteShader(fs);
    error = "shader: " + error;
    return 0;
  }
  GLuint program = gl.CreateProgram();
  gl.AttachShader(program, vs);
  gl.AttachShader(program, fs);
  gl.LinkProgram(program);
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint linked = 0;
  gl.GetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) {
    gl.DeleteProgram(program);
    error = "shader program did not link";
    return 0;
  }
  return program;
}

// Writes `vertices` relative to `eye` as floats (3 per vertex) into `buffer` from offset 0. GL gets
// eye-relative positions because floats far from the origin cannot resolve a pixel near the eye;
// the subtraction is done in double. `scratch` is reused between calls (no allocation once sized).
inline void uploadEyeRelative(GladGLContext& gl, GLuint buffer, std::span<const glm::dvec3> vertices,
                              const glm::dvec3& eye, std::vector<float>& scratch) {
  scratch.resize(vertices.size() * 3);
  for (size_t v = 0; v < vertices.size(); ++v) {
    const glm::dvec3 p = vertices[v] - eye;
    scratch[3 * v] = static_cast<float>(p.x);
    scratch[3 * v + 1] = static_cast<float>(p.y);
    scratch[3 * v + 2] = static_cast<float>(p.z);
  }
  if (!scratch.empty())
    gl.NamedBufferSubData(buffer, 0, static_cast<GLsizeiptr>(scratch.size() * sizeof(float)), scratch.data());
}

}  // namespace walkvis::gl_detail
