// Walkthrough drawing on the current GL 4.5 core context (scene_drawer.h). GL entry points come from
// a glad 2 "--mx" GladGLContext per drawer, loaded through the caller's loader: a GLFW window and
// OSMesa can live in one process, and libOSMesa and libOpenGL both export the GL API, so calling
// gl* symbols directly could reach the wrong library; a per-drawer function table cannot.
//
// Per frame the drawer copies the precomputed fan triangles of the fragments to draw, in order, into
// one index buffer and issues one glDrawElements (two with a highlight): GL rasterises primitives
// in order, so painter's order is kept, and llvmpipe pays its per-draw cost once rather than per
// fragment. Vertex positions are sent relative to the eye (computed in double), which keeps float
// precision close to the eye, as renderer.cpp does.
#include "walkthrough/scene_drawer.h"

#include <glad/gl.h>

#include "walkthrough/gl_program.h"

#include <algorithm>
#include <cstring>

#include <glm/geometric.hpp>

namespace walkvis {
namespace {

const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 pos;
layout(location = 1) in uint color;
layout(location = 2) in uint id;
layout(location = 3) in vec3 normal;
uniform mat4 clip;
out vec3 v_pos;
flat out vec3 v_color;
flat out uint v_id;
flat out vec3 v_normal;
void main() {
  gl_Position = clip * vec4(pos, 1.0);
  v_pos = pos;
  v_color = vec3(float((color >> 16) & 255u), float((color >> 8) & 255u), float(color & 255u)) / 255.0;
  v_id = id;
  v_normal = normal;
}
)";

// style 0: shaded, face colour times a head-light term |n · to-eye| (both sides lit alike, so a
// back face seen through a painter's list looks like its front); style 1: ids as RGBA8 bytes.
const char* kFragmentShader = R"(#version 450 core
in vec3 v_pos;
flat in vec3 v_color;
flat in uint v_id;
flat in vec3 v_normal;
uniform int style;
uniform int marker;
layout(location = 0) out vec4 o_color;
void main() {
  if (style == 1) {
    o_color = vec4(float(v_id & 255u), float((v_id >> 8) & 255u), float((v_id >> 16) & 255u),
                   float(v_id >> 24)) / 255.0;
  } else if (marker == 1) {
    o_color = vec4(1.0, 0.0, 1.0, 1.0);
  } else {
    float l = abs(dot(v_normal, normalize(-v_pos)));
    o_color = vec4(v_color * (0.3 + 0.7 * l), 1.0);
  }
}
)";

GLADapiproc loadThrough(void* user, const char* name) {
  const GlLoader loader = *static_cast<const GlLoader*>(user);
  return reinterpret_cast<GLADapiproc>(loader(name));
}

}  // namespace

struct SceneDrawer::Impl {
  GladGLContext gl{};
  GLuint program = 0;
  GLint clip_location = -1, style_location = -1, marker_location = -1;
  GLuint vao = 0, pos_buffer = 0, color_buffer = 0, id_buffer = 0, normal_buffer = 0, index_buffer = 0;
  size_t index_capacity = 0;  // in indices
  // Free triangles (mesh objects): their own vertex array, refilled per call.
  GLuint object_vao = 0, object_buffers[4] = {0, 0, 0, 0};
  size_t object_capacity = 0;  // in vertices
  std::vector<float> object_pos, object_normal;
  std::vector<uint32_t> object_color, object_id;

  std::vector<glm::dvec3> vertices;     // per fragment, consecutive
  std::vector<uint32_t> fan_indices;    // fragment f's triangles: fan_indices[fan_start[f], fan_start[f + 1])
  std::vector<uint32_t> fan_start;
  std::vector<float> eye_relative;      // 3 floats per vertex, for last_eye
  std::vector<uint32_t> frame_indices;  // reused per draw
  std::vector<uint8_t> rgba;            // reused per readback
  glm::dvec3 last_eye{0.0};
  bool positions_valid = false;

  ~Impl() {
    // The context may already be gone (a window closed first); only delete what a live table names.
    // Callers destroy the drawer while its context is current (scene_drawer.h).
    if (!gl.DeleteProgram || program == 0) return;
    gl.DeleteProgram(program);
    GLuint buffers[] = {pos_buffer, color_buffer, id_buffer, normal_buffer, index_buffer};
    gl.DeleteBuffers(5, buffers);
    gl.DeleteVertexArrays(1, &vao);
    gl.DeleteBuffers(4, object_buffers);
    gl.DeleteVertexArrays(1, &object_vao);
  }

  void updatePositions(const glm::dvec3& eye) {
    if (positions_valid && eye == last_eye) return;
    gl_detail::uploadEyeRelative(gl, pos_buffer, vertices, eye, eye_relative);
    last_eye = eye;
    positions_valid = true;
  }

  // Appends the triangles of draw[begin, end) to frame_indices; returns the index count added.
  size_t appendFans(std::span<const uint32_t> draw) {
    const size_t before = frame_indices.size();
    const size_t n = fan_start.empty() ? 0 : fan_start.size() - 1;
    for (uint32_t f : draw) {
      if (f >= n) continue;
      frame_indices.insert(frame_indices.end(), fan_indices.begin() + fan_start[f],
                           fan_indices.begin() + fan_start[f + 1]);
    }
    return frame_indices.size() - before;
  }
};

SceneDrawer::SceneDrawer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SceneDrawer::SceneDrawer(SceneDrawer&&) noexcept = default;
SceneDrawer& SceneDrawer::operator=(SceneDrawer&&) noexcept = default;
SceneDrawer::~SceneDrawer() = default;

std::optional<SceneDrawer> SceneDrawer::create(GlLoader loader, std::string* why) {
  auto fail = [&](const std::string& message) -> std::optional<SceneDrawer> {
    if (why) *why = message;
    return std::nullopt;
  };
  if (!loader) return fail("no GL loader");
  auto impl = std::make_unique<Impl>();
  GladGLContext& gl = impl->gl;
  GlLoader user = loader;
  const int version = gladLoadGLContextUserPtr(&gl, loadThrough, &user);
  if (version == 0 || GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 45)
    return fail("GL 4.5 core functions could not be loaded (is a GL 4.5 context current?)");

  std::string error;
  impl->program = gl_detail::buildProgram(gl, kVertexShader, kFragmentShader, error);
  if (impl->program == 0) return fail(error);
  impl->clip_location = gl.GetUniformLocation(impl->program, "clip");
  impl->style_location = gl.GetUniformLocation(impl->program, "style");
  impl->marker_location = gl.GetUniformLocation(impl->program, "marker");

  gl.CreateVertexArrays(1, &impl->vao);
  GLuint buffers[5];
  gl.CreateBuffers(5, buffers);
  impl->pos_buffer = buffers[0];
  impl->color_buffer = buffers[1];
  impl->id_buffer = buffers[2];
  impl->normal_buffer = buffers[3];
  impl->index_buffer = buffers[4];
  const GLuint vao = impl->vao;
  gl.VertexArrayVertexBuffer(vao, 0, impl->pos_buffer, 0, 3 * sizeof(float));
  gl.VertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  gl.VertexArrayVertexBuffer(vao, 1, impl->color_buffer, 0, sizeof(uint32_t));
  gl.VertexArrayAttribIFormat(vao, 1, 1, GL_UNSIGNED_INT, 0);
  gl.VertexArrayVertexBuffer(vao, 2, impl->id_buffer, 0, sizeof(uint32_t));
  gl.VertexArrayAttribIFormat(vao, 2, 1, GL_UNSIGNED_INT, 0);
  gl.VertexArrayVertexBuffer(vao, 3, impl->normal_buffer, 0, 3 * sizeof(float));
  gl.VertexArrayAttribFormat(vao, 3, 3, GL_FLOAT, GL_FALSE, 0);
  for (GLuint a = 0; a < 4; ++a) {
    gl.VertexArrayAttribBinding(vao, a, a);
    gl.EnableVertexArrayAttrib(vao, a);
  }
  gl.VertexArrayElementBuffer(vao, impl->index_buffer);
  // The object array: the same attribute layout over its own buffers.
  gl.CreateVertexArrays(1, &impl->object_vao);
  gl.CreateBuffers(4, impl->object_buffers);
  const GLuint ovao = impl->object_vao;
  gl.VertexArrayVertexBuffer(ovao, 0, impl->object_buffers[0], 0, 3 * sizeof(float));
  gl.VertexArrayAttribFormat(ovao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  gl.VertexArrayVertexBuffer(ovao, 1, impl->object_buffers[1], 0, sizeof(uint32_t));
  gl.VertexArrayAttribIFormat(ovao, 1, 1, GL_UNSIGNED_INT, 0);
  gl.VertexArrayVertexBuffer(ovao, 2, impl->object_buffers[2], 0, sizeof(uint32_t));
  gl.VertexArrayAttribIFormat(ovao, 2, 1, GL_UNSIGNED_INT, 0);
  gl.VertexArrayVertexBuffer(ovao, 3, impl->object_buffers[3], 0, 3 * sizeof(float));
  gl.VertexArrayAttribFormat(ovao, 3, 3, GL_FLOAT, GL_FALSE, 0);
  for (GLuint a = 0; a < 4; ++a) {
    gl.VertexArrayAttribBinding(ovao, a, a);
    gl.EnableVertexArrayAttrib(ovao, a);
  }
  if (gl.GetError() != GL_NO_ERROR) return fail("GL error while setting up the drawer");
  return SceneDrawer(std::move(impl));
}

void SceneDrawer::upload(const BspTree& bsp, const Scene& scene) {
  Impl& s = *impl_;
  GladGLContext& gl = s.gl;
  const size_t n = bsp.fragments.size();
  s.vertices.clear();
  s.fan_indices.clear();
  s.fan_start.assign(1, 0);
  std::vector<uint32_t> colors, ids;
  std::vector<float> normals;
  for (size_t f = 0; f < n; ++f) {
    const Polygon& p = bsp.fragments[f];
    const bool valid = p.vertex_count >= 3 && p.first_vertex <= bsp.vertices.size() &&
                       p.vertex_count <= bsp.vertices.size() - p.first_vertex;
    if (valid) {
      const uint32_t base = static_cast<uint32_t>(s.vertices.size());
      const uint32_t color = p.face_id < scene.face_colors.size() ? scene.face_colors[p.face_id] : faceColor(p.face_id);
      for (uint32_t v = 0; v < p.vertex_count; ++v) {
        s.vertices.push_back(bsp.vertices[p.first_vertex + v]);
        colors.push_back(color);
        ids.push_back(static_cast<uint32_t>(f + 1));
        normals.push_back(static_cast<float>(p.plane.n.x));
        normals.push_back(static_cast<float>(p.plane.n.y));
        normals.push_back(static_cast<float>(p.plane.n.z));
      }
      for (uint32_t v = 1; v + 1 < p.vertex_count; ++v) {
        s.fan_indices.push_back(base);
        s.fan_indices.push_back(base + v);
        s.fan_indices.push_back(base + v + 1);
      }
    }
    s.fan_start.push_back(static_cast<uint32_t>(s.fan_indices.size()));
  }
  s.positions_valid = false;
  const size_t nv = std::max<size_t>(s.vertices.size(), 1);
  colors.resize(nv, 0);
  ids.resize(nv, 0);
  normals.resize(nv * 3, 0.0f);
  gl.NamedBufferData(s.pos_buffer, static_cast<GLsizeiptr>(nv * 3 * sizeof(float)), nullptr, GL_DYNAMIC_DRAW);
  gl.NamedBufferData(s.color_buffer, static_cast<GLsizeiptr>(nv * sizeof(uint32_t)), colors.data(), GL_STATIC_DRAW);
  gl.NamedBufferData(s.id_buffer, static_cast<GLsizeiptr>(nv * sizeof(uint32_t)), ids.data(), GL_STATIC_DRAW);
  gl.NamedBufferData(s.normal_buffer, static_cast<GLsizeiptr>(nv * 3 * sizeof(float)), normals.data(),
                     GL_STATIC_DRAW);
  // Room for every fragment once: a frame draws each at most once in practice, so no reallocation.
  s.index_capacity = std::max<size_t>(s.fan_indices.size(), 3);
  gl.NamedBufferData(s.index_buffer, static_cast<GLsizeiptr>(s.index_capacity * sizeof(uint32_t)), nullptr,
                     GL_STREAM_DRAW);
  s.frame_indices.reserve(s.index_capacity);
  s.eye_relative.reserve(s.vertices.size() * 3);
}

void SceneDrawer::draw(const FreeCamera& camera, std::span<const uint32_t> draw, const DrawSettings& settings) {
  Impl& s = *impl_;
  GladGLContext& gl = s.gl;
  s.updatePositions(camera.eye);
  gl.Viewport(0, 0, camera.width, camera.height);
  const bool ids = settings.style == DrawStyle::kIds;
  if (ids) {
    gl.ClearColor(0.0f, 0.0f, 0.0f, 0.0f);
  } else {
    gl.ClearColor(0.12f, 0.13f, 0.16f, 1.0f);
  }
  gl.ClearDepth(1.0);
  gl.DepthMask(GL_TRUE);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (settings.depth_test) {
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_LESS);
  } else if (settings.write_depth) {
    // GL writes depth only with the depth test enabled; ALWAYS makes the test pass, so colour
    // and depth both come from the last polygon drawn over each pixel.
    gl.Enable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_ALWAYS);
  } else {
    gl.Disable(GL_DEPTH_TEST);
  }
  if (settings.cull_back_faces) {
    gl.Enable(GL_CULL_FACE);
    gl.CullFace(GL_BACK);
    gl.FrontFace(GL_CCW);
  } else {
    gl.Disable(GL_CULL_FACE);
  }
  gl.PolygonMode(GL_FRONT_AND_BACK, settings.wireframe ? GL_LINE : GL_FILL);
  gl.Disable(GL_BLEND);
  gl.Disable(GL_DITHER);  // ids must reach the buffer bit-exact
  gl.Disable(GL_MULTISAMPLE);
  gl.UseProgram(s.program);
  const std::array<float, 16> clip = clipFromEyeRelative(camera);
  gl.UniformMatrix4fv(s.clip_location, 1, GL_FALSE, clip.data());
  gl.Uniform1i(s.style_location, ids ? 1 : 0);
  gl.Uniform1i(s.marker_location, 0);
  gl.BindVertexArray(s.vao);

  s.frame_indices.clear();
  const size_t split = std::min<size_t>(settings.highlight_from, draw.size());
  const size_t first_count = s.appendFans(draw.first(split));
  const size_t second_count = s.appendFans(draw.subspan(split));
  const size_t total = first_count + second_count;
  if (total == 0) return;
  if (total > s.index_capacity) {
    s.index_capacity = total * 3 / 2;
    gl.NamedBufferData(s.index_buffer, static_cast<GLsizeiptr>(s.index_capacity * sizeof(uint32_t)), nullptr,
                       GL_STREAM_DRAW);
  }
  gl.NamedBufferSubData(s.index_buffer, 0, static_cast<GLsizeiptr>(total * sizeof(uint32_t)),
                        s.frame_indices.data());
  if (first_count > 0) gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(first_count), GL_UNSIGNED_INT, nullptr);
  if (second_count > 0) {
    gl.Uniform1i(s.marker_location, 1);
    gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(second_count), GL_UNSIGNED_INT,
                    reinterpret_cast<const void*>(first_count * sizeof(uint32_t)));
  }
}

void SceneDrawer::drawTriangles(const FreeCamera& camera, std::span<const glm::dvec3> corners,
                                std::span<const uint32_t> ids, uint32_t color, const DrawSettings& settings) {
  Impl& s = *impl_;
  GladGLContext& gl = s.gl;
  const size_t tris = std::min(corners.size() / 3, ids.size());
  if (tris == 0) return;
  const size_t nv = 3 * tris;
  s.object_pos.resize(3 * nv);
  s.object_normal.resize(3 * nv);
  s.object_color.assign(nv, color);
  s.object_id.resize(nv);
  for (size_t t = 0; t < tris; ++t) {
    // Eye-relative in double, then float (as the fragments); the normal of the exact triangle.
    const glm::dvec3 a = corners[3 * t] - camera.eye, b = corners[3 * t + 1] - camera.eye,
                     c = corners[3 * t + 2] - camera.eye;
    glm::dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    n = len > 0.0 ? n / len : glm::dvec3(0.0);
    const glm::dvec3 p[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const size_t v = 3 * t + static_cast<size_t>(k);
      for (int d = 0; d < 3; ++d) {
        s.object_pos[3 * v + d] = static_cast<float>(p[k][d]);
        s.object_normal[3 * v + d] = static_cast<float>(n[d]);
      }
      s.object_id[v] = ids[t] + 1;
    }
  }
  if (nv > s.object_capacity) {
    s.object_capacity = nv * 3 / 2;
    gl.NamedBufferData(s.object_buffers[0], static_cast<GLsizeiptr>(s.object_capacity * 3 * sizeof(float)), nullptr,
                       GL_STREAM_DRAW);
    gl.NamedBufferData(s.object_buffers[1], static_cast<GLsizeiptr>(s.object_capacity * sizeof(uint32_t)), nullptr,
                       GL_STREAM_DRAW);
    gl.NamedBufferData(s.object_buffers[2], static_cast<GLsizeiptr>(s.object_capacity * sizeof(uint32_t)), nullptr,
                       GL_STREAM_DRAW);
    gl.NamedBufferData(s.object_buffers[3], static_cast<GLsizeiptr>(s.object_capacity * 3 * sizeof(float)), nullptr,
                       GL_STREAM_DRAW);
  }
  gl.NamedBufferSubData(s.object_buffers[0], 0, static_cast<GLsizeiptr>(nv * 3 * sizeof(float)), s.object_pos.data());
  gl.NamedBufferSubData(s.object_buffers[1], 0, static_cast<GLsizeiptr>(nv * sizeof(uint32_t)),
                        s.object_color.data());
  gl.NamedBufferSubData(s.object_buffers[2], 0, static_cast<GLsizeiptr>(nv * sizeof(uint32_t)), s.object_id.data());
  gl.NamedBufferSubData(s.object_buffers[3], 0, static_cast<GLsizeiptr>(nv * 3 * sizeof(float)),
                        s.object_normal.data());
  gl.Viewport(0, 0, camera.width, camera.height);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_LESS);
  gl.DepthMask(GL_TRUE);
  gl.Disable(GL_CULL_FACE);
  gl.PolygonMode(GL_FRONT_AND_BACK, settings.wireframe ? GL_LINE : GL_FILL);
  gl.UseProgram(s.program);
  const std::array<float, 16> clip = clipFromEyeRelative(camera);
  gl.UniformMatrix4fv(s.clip_location, 1, GL_FALSE, clip.data());
  gl.Uniform1i(s.style_location, settings.style == DrawStyle::kIds ? 1 : 0);
  gl.Uniform1i(s.marker_location, 0);
  gl.BindVertexArray(s.object_vao);
  gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(nv));
  gl.BindVertexArray(s.vao);
}

void SceneDrawer::readRgb(int width, int height, std::vector<uint8_t>& rgb) {
  Impl& s = *impl_;
  const size_t w = static_cast<size_t>(std::max(width, 0)), h = static_cast<size_t>(std::max(height, 0));
  rgb.resize(w * h * 3);
  if (rgb.empty()) return;
  s.gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  s.gl.ReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  // GL rows start at the bottom; images start at the top.
  const size_t row = w * 3;
  for (size_t r = 0; r < h / 2; ++r)
    std::swap_ranges(rgb.begin() + r * row, rgb.begin() + (r + 1) * row, rgb.begin() + (h - 1 - r) * row);
}

void SceneDrawer::readIds(int width, int height, std::vector<uint32_t>& ids) {
  Impl& s = *impl_;
  const size_t w = static_cast<size_t>(std::max(width, 0)), h = static_cast<size_t>(std::max(height, 0));
  ids.resize(w * h);
  if (ids.empty()) return;
  s.rgba.resize(w * h * 4);
  s.gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
  s.gl.ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, s.rgba.data());
  for (size_t r = 0; r < h; ++r) {
    const uint8_t* src = s.rgba.data() + (h - 1 - r) * w * 4;
    for (size_t c = 0; c < w; ++c, src += 4) {
      const uint32_t v = uint32_t(src[0]) | uint32_t(src[1]) << 8 | uint32_t(src[2]) << 16 | uint32_t(src[3]) << 24;
      ids[r * w + c] = v == 0 ? kNoFragment : v - 1;
    }
  }
}

void SceneDrawer::finish() { impl_->gl.Finish(); }

}  // namespace walkvis
