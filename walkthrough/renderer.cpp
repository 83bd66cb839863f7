// Offscreen ID-buffer renderer on OSMesa (Mesa's software GL, llvmpipe) with a GL 4.5 core context.
// GL entry points come from a glad 2 "--mx" GladGLContext loaded through OSMesaGetProcAddress:
// libOSMesa and libOpenGL both export the GL API, so calling gl* symbols directly could reach the
// wrong library; a per-context function table cannot.
//
// Ids go into a GL_R32UI colour attachment (polygon index + 1, 0 = nothing), so no colour
// quantisation can merge two ids. Vertex positions are sent relative to the eye (computed in double),
// which keeps float precision where it matters, close to the eye.
#include "walkthrough/renderer.h"

// glad first: it stands in for GL/gl.h, which osmesa.h would otherwise include.
#include <glad/gl.h>

#include "walkthrough/gl_program.h"
// clang-format off
#include <GL/osmesa.h>
// clang-format on

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <glm/geometric.hpp>

namespace walkvis {
namespace {

const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec3 pos;
layout(location = 1) in uint id;
uniform mat4 clip;
flat out uint v_id;
void main() {
  gl_Position = clip * vec4(pos, 1.0);
  v_id = id;
}
)";

const char* kFragmentShader = R"(#version 450 core
flat in uint v_id;
layout(location = 0) out uint o_id;
void main() { o_id = v_id; }
)";

GLADapiproc loadOsMesa(const char* name) { return reinterpret_cast<GLADapiproc>(OSMesaGetProcAddress(name)); }

}  // namespace

struct OffscreenRenderer::Impl {
  OSMesaContext osmesa = nullptr;
  std::vector<uint8_t> default_buffer;  // OSMesa needs a buffer to make a context current
  GladGLContext gl{};
  int size = 0;
  int depth_bits = 0;
  const char* depth_format = "";
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  GLuint program = 0;
  GLint clip_location = -1;
  GLuint vao = 0, pos_buffer = 0, id_buffer = 0, order_index_buffer = 0;
  size_t order_index_capacity = 0;
  std::vector<uint32_t> all_order;  // 0, 1, ..., n - 1: the z-buffer's drawing order

  std::vector<glm::dvec3> vertices;
  std::vector<uint32_t> fan_indices;    // all polygons' fan triangles, 3 vertex indices each
  std::vector<uint32_t> fan_start;      // polygon k's triangles: fan_indices[fan_start[k], fan_start[k + 1])
  std::vector<float> eye_relative;      // 3 floats per vertex, for last_eye
  std::vector<uint32_t> order_indices;  // reused per draw
  std::vector<Ball> balls;              // per polygon: around its corners
  std::vector<uint8_t> outside;         // per polygon, for the current view: entirely outside the frustum
  glm::dvec3 last_eye{0.0};
  bool positions_valid = false;

  ~Impl() {
    if (!osmesa) return;
    if (OSMesaGetCurrentContext() != osmesa &&
        !OSMesaMakeCurrent(osmesa, default_buffer.data(), GL_UNSIGNED_BYTE, size, size)) {
      OSMesaDestroyContext(osmesa);
      return;
    }
    if (gl.DeleteProgram) {
      gl.DeleteProgram(program);
      GLuint buffers[] = {pos_buffer, id_buffer, order_index_buffer};
      gl.DeleteBuffers(3, buffers);
      gl.DeleteVertexArrays(1, &vao);
      GLuint rbs[] = {color_rb, depth_rb};
      gl.DeleteRenderbuffers(2, rbs);
      gl.DeleteFramebuffers(1, &fbo);
    }
    // Unbind first: a later context could reuse this address and be taken for current.
    OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
    OSMesaDestroyContext(osmesa);
  }

  void makeCurrent() {
    // OSMesa binds a context per thread; renderers for several depth formats take turns.
    if (OSMesaGetCurrentContext() != osmesa) {
      if (!OSMesaMakeCurrent(osmesa, default_buffer.data(), GL_UNSIGNED_BYTE, size, size))
        throw std::runtime_error("OSMesaMakeCurrent failed");
    }
  }

  void updatePositions(const glm::dvec3& eye) {
    if (positions_valid && eye == last_eye) return;
    gl_detail::uploadEyeRelative(gl, pos_buffer, vertices, eye, eye_relative);
    last_eye = eye;
    positions_valid = true;
  }

  // Frustum culling on the CPU: llvmpipe transforms every vertex it is given, and a cube face sees
  // about a sixth of the scene. A polygon is skipped only when its ball lies wholly outside the
  // view (ViewFrustum, with its margin for the float positions GL receives), so it could not have
  // covered a pixel: the image is unchanged.
  void cullToFrustum(const View& view) {
    const ViewFrustum frustum = viewFrustum(view);
    outside.resize(balls.size());
    for (size_t k = 0; k < balls.size(); ++k) outside[k] = frustum.excludesBall(balls[k].centre, balls[k].radius);
  }

  void begin(const View& view, bool depth_test) {
    makeCurrent();
    updatePositions(view.eye);
    cullToFrustum(view);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl.Viewport(0, 0, size, size);
    const GLuint zero[4] = {0, 0, 0, 0};
    gl.ClearBufferuiv(GL_COLOR, 0, zero);
    const GLfloat one = 1.0f;
    gl.ClearBufferfv(GL_DEPTH, 0, &one);
    if (depth_test) {
      gl.Enable(GL_DEPTH_TEST);
      gl.DepthFunc(GL_LESS);
      gl.DepthMask(GL_TRUE);
    } else {
      gl.Disable(GL_DEPTH_TEST);
    }
    gl.Enable(GL_CULL_FACE);
    gl.CullFace(GL_BACK);
    gl.FrontFace(GL_CCW);
    gl.Disable(GL_BLEND);
    gl.Disable(GL_MULTISAMPLE);
    gl.UseProgram(program);
    const std::array<float, 16> clip = clipFromEyeRelative(view);
    gl.UniformMatrix4fv(clip_location, 1, GL_FALSE, clip.data());
    gl.BindVertexArray(vao);
  }

  void drawOrder(std::span<const uint32_t> order) {
    order_indices.clear();
    const size_t n = fan_start.empty() ? 0 : fan_start.size() - 1;
    for (uint32_t k : order) {
      if (k >= n || outside[k]) continue;
      order_indices.insert(order_indices.end(), fan_indices.begin() + fan_start[k],
                           fan_indices.begin() + fan_start[k + 1]);
    }
    if (order_indices.empty()) return;
    const GLsizeiptr bytes = static_cast<GLsizeiptr>(order_indices.size() * sizeof(uint32_t));
    if (order_indices.size() > order_index_capacity) {
      order_index_capacity = order_indices.size() * 3 / 2;
      gl.NamedBufferData(order_index_buffer, static_cast<GLsizeiptr>(order_index_capacity * sizeof(uint32_t)),
                         nullptr, GL_STREAM_DRAW);
    }
    gl.NamedBufferSubData(order_index_buffer, 0, bytes, order_indices.data());
    gl.VertexArrayElementBuffer(vao, order_index_buffer);
    gl.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(order_indices.size()), GL_UNSIGNED_INT, nullptr);
  }
};

OffscreenRenderer::OffscreenRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OffscreenRenderer::OffscreenRenderer(OffscreenRenderer&&) noexcept = default;
OffscreenRenderer& OffscreenRenderer::operator=(OffscreenRenderer&&) noexcept = default;
OffscreenRenderer::~OffscreenRenderer() = default;

std::optional<OffscreenRenderer> OffscreenRenderer::create(int size, int depth_bits, std::string* why) {
  auto fail = [&](const std::string& message) -> std::optional<OffscreenRenderer> {
    if (why) *why = message;
    return std::nullopt;
  };
  if (size <= 0 || size > 16384) return fail("image size out of range");
  if (depth_bits != 16 && depth_bits != 24 && depth_bits != 32) return fail("depth bits must be 16, 24 or 32");
  auto impl = std::make_unique<Impl>();
  impl->size = size;
  impl->depth_bits = depth_bits;
  const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0, OSMESA_STENCIL_BITS, 0,
                            OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
  impl->osmesa = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!impl->osmesa) return fail("OSMesa could not create a GL 4.5 core context");
  impl->default_buffer.assign(static_cast<size_t>(size) * size * 4, 0);
  if (!OSMesaMakeCurrent(impl->osmesa, impl->default_buffer.data(), GL_UNSIGNED_BYTE, size, size))
    return fail("OSMesaMakeCurrent failed");
  GladGLContext& gl = impl->gl;
  const int version = gladLoadGLContext(&gl, loadOsMesa);
  if (version == 0 || GLAD_VERSION_MAJOR(version) * 10 + GLAD_VERSION_MINOR(version) < 45)
    return fail("GL 4.5 functions could not be loaded through OSMesaGetProcAddress");

  std::string error;
  impl->program = gl_detail::buildProgram(gl, kVertexShader, kFragmentShader, error);
  if (impl->program == 0) return fail(error);
  impl->clip_location = gl.GetUniformLocation(impl->program, "clip");

  gl.CreateFramebuffers(1, &impl->fbo);
  gl.CreateRenderbuffers(1, &impl->color_rb);
  gl.NamedRenderbufferStorage(impl->color_rb, GL_R32UI, size, size);
  gl.NamedFramebufferRenderbuffer(impl->fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, impl->color_rb);
  auto attachDepth = [&](GLenum format) {
    if (impl->depth_rb) gl.DeleteRenderbuffers(1, &impl->depth_rb);
    gl.CreateRenderbuffers(1, &impl->depth_rb);
    gl.NamedRenderbufferStorage(impl->depth_rb, format, size, size);
    gl.NamedFramebufferRenderbuffer(impl->fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, impl->depth_rb);
    GLint bits = 0;
    gl.GetNamedRenderbufferParameteriv(impl->depth_rb, GL_RENDERBUFFER_DEPTH_SIZE, &bits);
    return gl.CheckNamedFramebufferStatus(impl->fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE &&
           bits >= depth_bits;
  };
  bool complete = false;
  if (depth_bits == 16) {
    complete = attachDepth(GL_DEPTH_COMPONENT16);
    impl->depth_format = "DEPTH_COMPONENT16";
  } else if (depth_bits == 24) {
    complete = attachDepth(GL_DEPTH_COMPONENT24);
    impl->depth_format = "DEPTH_COMPONENT24";
  } else {
    complete = attachDepth(GL_DEPTH_COMPONENT32);
    impl->depth_format = "DEPTH_COMPONENT32";
    if (!complete) {
      complete = attachDepth(GL_DEPTH_COMPONENT32F);
      impl->depth_format = "DEPTH_COMPONENT32F";
    }
  }
  if (!complete) return fail(std::string("framebuffer incomplete with ") + impl->depth_format);
  const GLenum draw_buffer = GL_COLOR_ATTACHMENT0;
  gl.NamedFramebufferDrawBuffers(impl->fbo, 1, &draw_buffer);
  gl.NamedFramebufferReadBuffer(impl->fbo, GL_COLOR_ATTACHMENT0);

  gl.CreateVertexArrays(1, &impl->vao);
  GLuint buffers[3];
  gl.CreateBuffers(3, buffers);
  impl->pos_buffer = buffers[0];
  impl->id_buffer = buffers[1];
  impl->order_index_buffer = buffers[2];
  gl.VertexArrayVertexBuffer(impl->vao, 0, impl->pos_buffer, 0, 3 * sizeof(float));
  gl.VertexArrayAttribFormat(impl->vao, 0, 3, GL_FLOAT, GL_FALSE, 0);
  gl.VertexArrayAttribBinding(impl->vao, 0, 0);
  gl.EnableVertexArrayAttrib(impl->vao, 0);
  gl.VertexArrayVertexBuffer(impl->vao, 1, impl->id_buffer, 0, sizeof(uint32_t));
  gl.VertexArrayAttribIFormat(impl->vao, 1, 1, GL_UNSIGNED_INT, 0);
  gl.VertexArrayAttribBinding(impl->vao, 1, 1);
  gl.EnableVertexArrayAttrib(impl->vao, 1);
  if (gl.GetError() != GL_NO_ERROR) return fail("GL error while setting up the renderer");
  return OffscreenRenderer(std::move(impl));
}

void OffscreenRenderer::upload(std::span<const glm::dvec3> vertices, std::span<const Polygon> polygons) {
  Impl& s = *impl_;
  s.makeCurrent();
  GladGLContext& gl = s.gl;
  s.vertices.assign(vertices.begin(), vertices.end());
  // The id attribute is per vertex: Scene polygons own consecutive vertices, but a caller's
  // polygons may share them, so every polygon gets its own copy of its vertex indices' slots.
  std::vector<uint32_t> ids;
  std::vector<glm::dvec3> own_vertices;
  own_vertices.reserve(vertices.size());
  ids.reserve(vertices.size());
  s.fan_indices.clear();
  s.fan_start.assign(1, 0);
  s.balls.assign(polygons.size(), Ball{});  // polygons with no valid vertices have no triangles to draw
  for (size_t k = 0; k < polygons.size(); ++k) {
    const Polygon& p = polygons[k];
    const bool valid = p.vertex_count >= 3 && p.first_vertex <= vertices.size() &&
                       p.vertex_count <= vertices.size() - p.first_vertex;
    if (valid) {
      const uint32_t base = static_cast<uint32_t>(own_vertices.size());
      for (uint32_t v = 0; v < p.vertex_count; ++v) {
        own_vertices.push_back(vertices[p.first_vertex + v]);
        ids.push_back(static_cast<uint32_t>(k + 1));
      }
      for (uint32_t v = 1; v + 1 < p.vertex_count; ++v) {
        s.fan_indices.push_back(base);
        s.fan_indices.push_back(base + v);
        s.fan_indices.push_back(base + v + 1);
      }
    }
    s.fan_start.push_back(static_cast<uint32_t>(s.fan_indices.size()));
    if (valid) s.balls[k] = polygonBall(vertices, p);
  }
  s.vertices = std::move(own_vertices);
  s.positions_valid = false;
  const size_t nv = std::max<size_t>(s.vertices.size(), 1);
  gl.NamedBufferData(s.pos_buffer, static_cast<GLsizeiptr>(nv * 3 * sizeof(float)), nullptr, GL_DYNAMIC_DRAW);
  ids.resize(nv, 0);
  gl.NamedBufferData(s.id_buffer, static_cast<GLsizeiptr>(nv * sizeof(uint32_t)), ids.data(), GL_STATIC_DRAW);
}

void OffscreenRenderer::drawPainter(const View& view, std::span<const uint32_t> order) {
  impl_->begin(view, false);
  impl_->drawOrder(order);
}

void OffscreenRenderer::drawZBuffer(const View& view, std::span<const uint32_t> order) {
  Impl& s = *impl_;
  s.begin(view, true);
  if (!order.empty()) {
    s.drawOrder(order);
  } else {
    s.all_order.resize(s.outside.size());
    for (size_t k = 0; k < s.all_order.size(); ++k) s.all_order[k] = static_cast<uint32_t>(k);
    s.drawOrder(s.all_order);
  }
}

void OffscreenRenderer::readIds(std::vector<uint32_t>& out) {
  Impl& s = *impl_;
  s.makeCurrent();
  const size_t n = static_cast<size_t>(s.size) * s.size;
  out.resize(n);
  s.gl.BindFramebuffer(GL_READ_FRAMEBUFFER, s.fbo);
  s.gl.PixelStorei(GL_PACK_ALIGNMENT, 4);
  s.gl.ReadPixels(0, 0, s.size, s.size, GL_RED_INTEGER, GL_UNSIGNED_INT, out.data());
  // GL rows start at the bottom; camera.h images start at the top.
  const size_t w = static_cast<size_t>(s.size);
  for (size_t r = 0; r < w / 2; ++r)
    std::swap_ranges(out.begin() + r * w, out.begin() + (r + 1) * w, out.begin() + (w - 1 - r) * w);
  for (uint32_t& id : out) id = id == 0 ? kNoPolygon : id - 1;
}

std::vector<uint32_t> OffscreenRenderer::readIds() {
  std::vector<uint32_t> out;
  readIds(out);
  return out;
}

int OffscreenRenderer::size() const { return impl_->size; }
int OffscreenRenderer::depthBits() const { return impl_->depth_bits; }
const char* OffscreenRenderer::depthFormat() const { return impl_->depth_format; }

std::string OffscreenRenderer::glRenderer() const {
  impl_->makeCurrent();
  const auto* renderer = reinterpret_cast<const char*>(impl_->gl.GetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(impl_->gl.GetString(GL_VERSION));
  return std::string(renderer ? renderer : "?") + ", " + (version ? version : "?");
}

}  // namespace walkvis
