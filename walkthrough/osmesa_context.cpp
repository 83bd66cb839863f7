// OSMesa context with a user colour buffer (RGBA, unsigned byte) as its default framebuffer; Mesa
// allocates the depth buffer at the requested bits.
#include "walkthrough/osmesa_context.h"

#include <GL/osmesa.h>

#include <stdexcept>

namespace walkvis {
namespace {

void* osmesaProc(const char* name) { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); }

}  // namespace

struct OsMesaContext::Impl {
  OSMesaContext osmesa = nullptr;
  std::vector<uint8_t> buffer;
  int width = 0, height = 0;
  ~Impl() {
    if (!osmesa) return;
    // Unbind first: a later context could reuse this address and be taken for current.
    if (OSMesaGetCurrentContext() == osmesa) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
    OSMesaDestroyContext(osmesa);
  }
};

OsMesaContext::OsMesaContext(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OsMesaContext::OsMesaContext(OsMesaContext&&) noexcept = default;
OsMesaContext& OsMesaContext::operator=(OsMesaContext&&) noexcept = default;
OsMesaContext::~OsMesaContext() = default;

std::optional<OsMesaContext> OsMesaContext::create(int width, int height, int depth_bits, std::string* why) {
  auto fail = [&](const std::string& message) -> std::optional<OsMesaContext> {
    if (why) *why = message;
    return std::nullopt;
  };
  if (width < 1 || height < 1 || width > 16384 || height > 16384) return fail("image size out of range");
  if (depth_bits != 16 && depth_bits != 24 && depth_bits != 32) return fail("depth bits must be 16, 24 or 32");
  auto impl = std::make_unique<Impl>();
  impl->width = width;
  impl->height = height;
  const int attributes[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, depth_bits, OSMESA_STENCIL_BITS, 0,
                            OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, 5, 0};
  impl->osmesa = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!impl->osmesa) return fail("OSMesa could not create a GL 4.5 core context");
  impl->buffer.assign(static_cast<size_t>(width) * height * 4, 0);
  OsMesaContext context(std::move(impl));
  try {
    context.makeCurrent();
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  return context;
}

void OsMesaContext::makeCurrent() {
  Impl& s = *impl_;
  if (OSMesaGetCurrentContext() == s.osmesa) return;
  if (!OSMesaMakeCurrent(s.osmesa, s.buffer.data(), GL_UNSIGNED_BYTE, s.width, s.height))
    throw std::runtime_error("OSMesaMakeCurrent failed");
}

int OsMesaContext::width() const { return impl_->width; }
int OsMesaContext::height() const { return impl_->height; }
GlLoader OsMesaContext::loader() { return &osmesaProc; }

}  // namespace walkvis
