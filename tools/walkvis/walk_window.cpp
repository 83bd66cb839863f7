// The walkthrough window: GLFW (OpenGL 4.5 core), the frame core (frame.h) and drawer
// (scene_drawer.h) shared with `walkvis render`, the walking physics (movement.h), and a Dear
// ImGui overlay. Every frame: move the eye, FrameBuilder::build, SceneDrawer::draw, overlay, swap.
#include "walk_window.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <vector>

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include "frames_common.h"
#include "walkthrough/camera_path.h"
#include "walkthrough/frame.h"
#include "walkthrough/movement.h"
#include "walkthrough/scene_drawer.h"
#include "walkthrough/validate.h"

namespace walkvis {
namespace {

constexpr double kMouseRadiansPerPixel = 0.0025;
constexpr double kMaxPitch = 1.5;                 // radians, below pi/2 (camera_path.h)
constexpr double kWalkEyeHeightsPerSecond = 2.0;  // as the automatic tour; Shift runs 3x
constexpr double kMaxFrameSeconds = 0.1;          // a stalled frame does not make a giant step

constexpr ListCullMethod kCullCycle[] = {ListCullMethod::kNone,    ListCullMethod::kPolygon,
                                         ListCullMethod::kMask,    ListCullMethod::kCluster,
                                         ListCullMethod::kHierarchy, ListCullMethod::kRegion};

bool isRunTimeMethod(ListCullMethod m) {
  return m == ListCullMethod::kPolygon || m == ListCullMethod::kMask || m == ListCullMethod::kCluster ||
         m == ListCullMethod::kHierarchy;
}

// Rebuilds the world's list cullers for another method (as openWorld builds them).
void setCullMethod(World& world, ListCullMethod method) {
  world.cull = method;
  world.all_culler.reset();
  world.run_cullers.clear();
  if (method == ListCullMethod::kNone) return;
  const BspTree& bsp = world.trees.bsp;
  const uint32_t n = static_cast<uint32_t>(bsp.fragments.size());
  const BackfaceInput input{bsp.vertices, bsp.fragments};
  world.all_fragments.resize(n);
  std::iota(world.all_fragments.begin(), world.all_fragments.end(), 0u);
  const IndexRange all{0, n};
  world.all_culler = std::make_unique<ListCuller>(
      ListCuller::build(input, world.all_fragments, std::span<const IndexRange>(&all, 1), method));
  if (!isRunTimeMethod(method)) return;
  std::vector<IndexRange> ranges;
  for (const PfdLevel& level : world.trees.levels) {
    auto& per_cell = world.run_cullers.emplace_back();
    for (const PfdTree& tree : level.cells) {
      ranges.clear();
      for (const PfdRun& r : tree.runs) ranges.push_back({r.first, r.count});
      per_cell.push_back(ListCuller::build(input, tree.fragment_ids, ranges, method));
    }
  }
}

// Input state shared with the GLFW callbacks (through the window's user pointer).
struct Input {
  bool captured = false;
  bool have_last = false;
  double last_x = 0.0, last_y = 0.0;
  double yaw_delta = 0.0, pitch_delta = 0.0;
  std::vector<int> pressed;  // keys pressed since the last frame
  bool quit = false;
};

void keyCallback(GLFWwindow* window, int key, int, int action, int) {
  if (action != GLFW_PRESS) return;
  auto* in = static_cast<Input*>(glfwGetWindowUserPointer(window));
  if (key == GLFW_KEY_ESCAPE) {
    if (in->captured) {
      in->captured = false;
      glfwSetInputMode(window, GLFW_CURSOR, GLFW_CURSOR_NORMAL);
    } else {
      in->quit = true;
    }
    return;
  }
  in->pressed.push_back(key);
}

void cursorCallback(GLFWwindow* window, double x, double y) {
  auto* in = static_cast<Input*>(glfwGetWindowUserPointer(window));
  if (in->captured && in->have_last) {
    in->yaw_delta -= (x - in->last_x) * kMouseRadiansPerPixel;  // right turns right: yaw decreases
    in->pitch_delta -= (y - in->last_y) * kMouseRadiansPerPixel;
  }
  in->last_x = x, in->last_y = y, in->have_last = true;
}

void mouseButtonCallback(GLFWwindow* window, int button, int action, int) {
  auto* in = static_cast<Input*>(glfwGetWindowUserPointer(window));
  if (button == GLFW_MOUSE_BUTTON_LEFT && action == GLFW_PRESS && !in->captured &&
      !ImGui::GetIO().WantCaptureMouse) {
    in->captured = true;
    in->have_last = false;
    glfwSetInputMode(window, GLFW_CURSOR, GLFW_CURSOR_DISABLED);
  }
}

struct GlfwSession {
  GlfwSession() {
    if (!glfwInit()) throw std::runtime_error("GLFW: cannot initialise (no display?)");
  }
  ~GlfwSession() { glfwTerminate(); }
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

struct ImGuiSession {
  explicit ImGuiSession(GLFWwindow* window) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working folder
    ImGui::StyleColorsDark();
    // Our callbacks are installed first; ImGui chains to them.
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 450 core");
  }
  ~ImGuiSession() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  ImGuiSession(const ImGuiSession&) = delete;
  ImGuiSession& operator=(const ImGuiSession&) = delete;
};

std::string screenshotName(const std::string& dir, const char* stem, size_t index) {
  char name[48];
  std::snprintf(name, sizeof name, "%s_%05zu.png", stem, index);
  return (std::filesystem::path(dir) / name).string();
}

}  // namespace

int runWalk(const WalkArgs& args) {
  const ImageSize size = parseImageSize(args.size, "--size");
  WorldOptions options;
  options.load = args.load;
  options.scene = args.scene;
  options.cull = parseListCullMethod(args.cull);
  options.objects = parseObjectSet(args.objects);
  std::optional<OrderMode> mode;
  if (!args.mode.empty()) mode = parseOrderMode(args.mode);
  options.build_pfd = mode == OrderMode::kPfd;
  std::optional<CameraPath> path;
  if (!args.path.empty()) path = loadCameraPath(args.path);  // bad files fail before any window opens
  if (args.quit_at_end && !path) throw Error("--quit-at-end needs --path");
  if (!args.screenshot_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(args.screenshot_dir, ec);
    if (ec || !std::filesystem::is_directory(args.screenshot_dir))
      throw Error(args.screenshot_dir + ": cannot create the screenshot folder");
  }
  auto progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  World world = openWorld(args.source, options, progress);
  if (!mode) mode = world.trees.levels.empty() ? OrderMode::kBsp
                    : world.trees.kind == TreeKind::kHfd ? OrderMode::kHfd
                                                         : OrderMode::kPfd;
  const Walker walker(world.scene, world.trees.bsp);

  const GlfwSession glfw;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  glfwWindowHint(GLFW_SAMPLES, 0);  // no multisampling: screenshots must match the offscreen frames
  // A path run keeps its size, so its screenshots have the size asked for.
  glfwWindowHint(GLFW_RESIZABLE, path ? GLFW_FALSE : GLFW_TRUE);
  const std::string title = "walkvis walk " + world.source;
  GLFWwindow* window = glfwCreateWindow(size.width, size.height, title.c_str(), nullptr, nullptr);
  if (!window) throw std::runtime_error("GLFW: cannot open an OpenGL 4.5 core window");
  struct WindowCloser {
    GLFWwindow* w;
    ~WindowCloser() { glfwDestroyWindow(w); }
  } closer{window};
  glfwMakeContextCurrent(window);
  glfwSwapInterval(path ? 0 : 1);
  std::string why;
  auto drawer = SceneDrawer::create(reinterpret_cast<GlLoader>(glfwGetProcAddress), &why);
  if (!drawer) throw std::runtime_error("OpenGL: " + why);
  drawer->upload(world.trees.bsp, world.scene);

  Input input;
  glfwSetWindowUserPointer(window, &input);
  glfwSetKeyCallback(window, keyCallback);
  glfwSetCursorPosCallback(window, cursorCallback);
  glfwSetMouseButtonCallback(window, mouseButtonCallback);
  const ImGuiSession imgui(window);

  WalkState state = walker.place(world.scene.start_eye);
  double yaw = world.scene.start_yaw, pitch = 0.0;
  bool wireframe = args.wireframe, show_rejected = args.show_rejected, overlay = !args.no_overlay;
  bool path_screens = path && !args.screenshot_dir.empty();
  DrawStyle style = args.ids ? DrawStyle::kIds : DrawStyle::kShaded;
  size_t path_index = 0, screenshots = 0;
  CameraPath recorded;
  FrameBuilder builder;
  std::vector<uint32_t> draw;
  std::vector<uint8_t> rgb, drawn_mark;
  FrameStats stats;
  double frame_ms_smooth = 0.0;
  const auto start = std::chrono::steady_clock::now();
  auto last = start;
  std::string message;

  while (!glfwWindowShouldClose(window) && !input.quit) {
    glfwPollEvents();
    const auto now = std::chrono::steady_clock::now();
    const double dt = std::min(std::chrono::duration<double>(now - last).count(), kMaxFrameSeconds);
    last = now;
    bool screenshot = false;
    for (int key : input.pressed) {
      if (ImGui::GetIO().WantCaptureKeyboard) break;
      switch (key) {
        case GLFW_KEY_1: mode = OrderMode::kZBuffer; break;
        case GLFW_KEY_2: mode = OrderMode::kBsp; break;
        case GLFW_KEY_3: mode = OrderMode::kPfd; break;
        case GLFW_KEY_4: mode = OrderMode::kHfd; break;
        case GLFW_KEY_B: {
          size_t i = 0;
          while (kCullCycle[i] != world.cull) ++i;
          setCullMethod(world, kCullCycle[(i + 1) % std::size(kCullCycle)]);
          break;
        }
        case GLFW_KEY_F: wireframe = !wireframe; break;
        case GLFW_KEY_R: show_rejected = !show_rejected; break;
        case GLFW_KEY_H: overlay = !overlay; break;
        case GLFW_KEY_I: style = style == DrawStyle::kIds ? DrawStyle::kShaded : DrawStyle::kIds; break;
        case GLFW_KEY_P:
        case GLFW_KEY_F12: screenshot = true; break;
        default: break;
      }
    }
    input.pressed.clear();

    if (path) {
      if (path_index >= path->keys.size()) {
        if (args.quit_at_end) break;
        path_index = path->keys.size() - 1;  // hold the last view
        path_screens = false;
      }
      const CameraKey& k = path->keys[path_index];
      state = {k.eye, walker.place(k.eye).level};
      yaw = k.yaw, pitch = k.pitch;
    } else {
      yaw = std::remainder(yaw + input.yaw_delta, 2.0 * std::numbers::pi);
      pitch = std::clamp(pitch + input.pitch_delta, -kMaxPitch, kMaxPitch);
      glm::dvec2 wish{0.0};
      const glm::dvec2 forward{-std::sin(yaw), -std::cos(yaw)}, right{std::cos(yaw), -std::sin(yaw)};
      if (!ImGui::GetIO().WantCaptureKeyboard) {
        if (glfwGetKey(window, GLFW_KEY_W) == GLFW_PRESS) wish += forward;
        if (glfwGetKey(window, GLFW_KEY_S) == GLFW_PRESS) wish -= forward;
        if (glfwGetKey(window, GLFW_KEY_D) == GLFW_PRESS) wish += right;
        if (glfwGetKey(window, GLFW_KEY_A) == GLFW_PRESS) wish -= right;
      }
      const double len = std::hypot(wish.x, wish.y);
      if (len > 0.0) {
        const bool run = glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS;
        const double speed = kWalkEyeHeightsPerSecond * world.scene.eye_height * (run ? 3.0 : 1.0);
        state = walker.move(state, wish / len * (speed * dt));
      }
    }
    input.yaw_delta = input.pitch_delta = 0.0;
    const double t = std::chrono::duration<double>(now - start).count();
    if (!args.record.empty())
      recorded.keys.push_back(path ? path->keys[path_index] : CameraKey{t, state.eye, yaw, pitch});

    int fb_w = 0, fb_h = 0;
    glfwGetFramebufferSize(window, &fb_w, &fb_h);
    if (fb_w <= 0 || fb_h <= 0) continue;  // minimised
    FreeCamera camera = cameraAt({t, state.eye, yaw, pitch}, {fb_w, fb_h});
    // The objects' clock: the path's time when following one (so screenshots equal `walkvis
    // render`'s frames of the same keys), the wall clock otherwise.
    const double object_time = path ? path->keys[path_index].time : t;
    stats = builder.build(world, camera, *mode, draw, object_time);
    DrawSettings settings = settingsFor(*mode, style, !world.objects.empty());
    settings.wireframe = wireframe;
    if (show_rejected) {
      // What the order and the culling left out but faces the eye, drawn last in the marker colour.
      drawn_mark.assign(world.trees.bsp.fragments.size(), 0);
      for (uint32_t f : draw) drawn_mark[f] = 1;
      settings.highlight_from = static_cast<uint32_t>(draw.size());
      for (uint32_t f = 0; f < drawn_mark.size(); ++f)
        if (!drawn_mark[f] && sideOfPlane(world.trees.bsp, f, camera.eye) > 0) draw.push_back(f);
    }
    const auto d0 = std::chrono::steady_clock::now();
    drawer->draw(camera, draw, settings);
    drawObjects(builder, *drawer, camera, settings);
    drawer->finish();
    stats.draw_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - d0).count();
    const double frame_ms = stats.order_ms + stats.object_ms + stats.draw_ms;
    frame_ms_smooth = frame_ms_smooth == 0.0 ? frame_ms : 0.9 * frame_ms_smooth + 0.1 * frame_ms;

    // Path screenshots are taken before the overlay is drawn (the scene only, to compare with
    // `walkvis render`) unless --screenshot-overlay; the P key shows what a person sees.
    const bool overlay_now = overlay && (!path_screens || args.screenshot_overlay);
    auto capture = [&] {
      const std::string dir = args.screenshot_dir.empty() ? "." : args.screenshot_dir;
      const std::string file = path_screens ? screenshotName(dir, "frame", path_index)
                                            : screenshotName(dir, "screenshot", screenshots++);
      drawer->readRgb(fb_w, fb_h, rgb);
      writePngRgb(file, fb_w, fb_h, rgb);
      if (!path_screens) message = "saved " + file;
    };
    const bool capture_now = path_screens || screenshot;
    if (capture_now && !(overlay_now && (screenshot || args.screenshot_overlay))) capture();

    if (overlay_now) {
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      ImGui::SetNextWindowPos({8, 8}, ImGuiCond_FirstUseEver);
      ImGui::SetNextWindowBgAlpha(0.7f);
      ImGui::Begin("walkvis", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
      ImGui::Text("%s", world.source.c_str());
      ImGui::Text("frame %.2f ms (order %.3f + draw %.2f), %.0f fps", frame_ms_smooth, stats.order_ms,
                  stats.draw_ms, ImGui::GetIO().Framerate);
      ImGui::Text("polygons drawn %u of %u (listed %u, culled %u, outside the view %u, occluded %u%s)", stats.drawn,
                  stats.scene_polygons, stats.listed, stats.culled, stats.outside, stats.occluded,
                  stats.occlusion_rested ? ", occlusion test resting" : "");
      ImGui::Text("tests per frame %u", stats.tests);
      if (!world.objects.empty())
        ImGui::Text("objects %zu: triangles drawn %u, computed %llu (Moller-Sequin culling), %.2f ms",
                    world.objects.size(), stats.object_triangles,
                    static_cast<unsigned long long>(stats.object_triangles_computed), stats.object_ms);
      ImGui::Text("mode [1-4] %s (used %s)   level tree %d   walk level %d",
                  std::string(orderModeName(*mode)).c_str(), std::string(orderModeName(stats.used)).c_str(),
                  stats.level, state.level);
      ImGui::Text("backface [B] %s   wireframe [F] %s   rejected [R] %s   ids [I] %s",
                  std::string(listCullMethodName(world.cull)).c_str(), wireframe ? "on" : "off",
                  show_rejected ? "on" : "off", style == DrawStyle::kIds ? "on" : "off");
      ImGui::Text("eye (%.2f, %.2f, %.2f) yaw %.1f deg pitch %.1f deg", state.eye.x, state.eye.y, state.eye.z,
                  yaw * 180.0 / std::numbers::pi, pitch * 180.0 / std::numbers::pi);
      if (path) ImGui::Text("path key %zu of %zu", std::min(path_index + 1, path->keys.size()), path->keys.size());
      if (!args.record.empty()) ImGui::Text("recording %zu keys to %s", recorded.keys.size(), args.record.c_str());
      ImGui::TextDisabled(input.captured ? "WASD walk, Shift run, mouse look, Esc release mouse, P screenshot"
                                         : "click to capture the mouse, Esc quits");
      if (!message.empty()) ImGui::TextDisabled("%s", message.c_str());
      ImGui::End();
      ImGui::Render();
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      if (capture_now && (screenshot || args.screenshot_overlay)) capture();
    }
    glfwSwapBuffers(window);
    if (path) ++path_index;
  }
  if (!args.record.empty() && !recorded.keys.empty()) {
    saveCameraPath(recorded, args.record);
    std::printf("recorded %zu keys to %s\n", recorded.keys.size(), args.record.c_str());
  }
  if (path_screens || (path && !args.screenshot_dir.empty()))
    std::printf("%zu path frames shown, screenshots in %s\n", path->keys.size(), args.screenshot_dir.c_str());
  return 0;
}

}  // namespace walkvis
