// The C API (bindings/c/dfbwall.h) over the C++ data-distributed API: every call catches what
// the C++ side throws and turns it into an error code, the thread's last message and the error
// function, so no exception crosses into C.
#include "bindings/c/dfbwall.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <exception>
#include <iterator>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "api/DataDistributed.h"

struct dfbwall_options {
  dfbwall::SessionOptions options;
};

struct dfbwall_style {
  dfbwall::Style style;
};

struct dfbwall_session {
  std::optional<dfbwall::Session> session;
  std::vector<std::uint8_t> image;  // what dfbwall_session_image points into
};

namespace {

thread_local std::string lastMessage;
thread_local dfbwall_error lastCode = DFBWALL_OK;

std::mutex functionMutex;
dfbwall_error_function errorFunction = nullptr;
void* errorUser = nullptr;

dfbwall_error fail(dfbwall_error code, const std::string& message) {
  lastCode = code;
  lastMessage = message;
  dfbwall_error_function function = nullptr;
  void* user = nullptr;
  {
    std::lock_guard lock(functionMutex);
    function = errorFunction;
    user = errorUser;
  }
  if (function) function(user, code, lastMessage.c_str());
  return code;
}

// Bad input found here, before the C++ API sees it.
class CInputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Runs `body`, turning whatever it throws into a code (the most specific class first).
template <class Body>
dfbwall_error guarded(Body&& body) noexcept {
  try {
    body();
    return DFBWALL_OK;
  } catch (const dfbwall::InputError& e) {
    return fail(DFBWALL_ERROR_INPUT, e.what());
  } catch (const CInputError& e) {
    return fail(DFBWALL_ERROR_INPUT, e.what());
  } catch (const std::logic_error& e) {
    return fail(DFBWALL_ERROR_USAGE, e.what());
  } catch (const std::bad_alloc&) {
    return fail(DFBWALL_ERROR_OUT_OF_MEMORY, "dfbwall: out of memory");
  } catch (const std::exception& e) {
    return fail(DFBWALL_ERROR_FAILED, e.what());
  } catch (...) {
    return fail(DFBWALL_ERROR_UNKNOWN, "dfbwall: an unknown error");
  }
}

template <class T>
T& need(T* handle, const char* what) {
  if (!handle) throw CInputError(std::string("dfbwall: ") + what + " is NULL");
  return *handle;
}

const char* text(const char* p, const char* what) {
  if (!p) throw CInputError(std::string("dfbwall: ") + what + " is NULL");
  return p;
}

dfbwall::Session& sessionOf(dfbwall_session* s) {
  dfbwall_session& h = need(s, "the session");
  return *h.session;
}

dfbwall::Vec3f vec(const float* v, const char* what) {
  if (!v) throw CInputError(std::string("dfbwall: ") + what + " is NULL");
  return {v[0], v[1], v[2]};
}

dfbwall::VolumeStyle& volumeOf(dfbwall_style* style, int volume) {
  dfbwall::Style& st = need(style, "the style").style;
  if (volume < 0 || static_cast<std::size_t>(volume) >= st.volumes.size())
    throw CInputError("dfbwall: volume " + std::to_string(volume) +
                      " is not in the style (it has " + std::to_string(st.volumes.size()) + ")");
  return st.volumes[static_cast<std::size_t>(volume)];
}

int parseInt(const char* key, const std::string& value) {
  std::size_t used = 0;
  int out = 0;
  try {
    out = std::stoi(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size())
    throw CInputError(std::string("dfbwall: option ") + key + ": '" + value +
                      "' is not an integer");
  return out;
}

float parseFloat(const char* key, const std::string& value) {
  std::size_t used = 0;
  float out = 0;
  try {
    out = std::stof(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size())
    throw CInputError(std::string("dfbwall: option ") + key + ": '" + value + "' is not a number");
  return out;
}

bool parseBool(const char* key, const std::string& value) {
  if (value == "1" || value == "true" || value == "on") return true;
  if (value == "0" || value == "false" || value == "off") return false;
  throw CInputError(std::string("dfbwall: option ") + key + ": '" + value + "' is not 1 or 0");
}

void setOption(dfbwall::SessionOptions& o, const char* key, const std::string& v) {
  const std::string k = key;
  if (k == "width")
    o.width = parseInt(key, v);
  else if (k == "height")
    o.height = parseInt(key, v);
  else if (k == "wall")
    o.wall = v;
  else if (k == "offscreen")
    o.offscreen = parseBool(key, v);
  else if (k == "capture")
    o.captureDir = v;
  else if (k == "capture-every")
    o.captureEvery = parseInt(key, v);
  else if (k == "tile-size")
    o.tileSize = parseInt(key, v);
  else if (k == "threads")
    o.threads = parseInt(key, v);
  else if (k == "frames-in-flight")
    o.framesInFlight = parseInt(key, v);
  else if (k == "timeout")
    o.timeoutSeconds = parseInt(key, v);
  else if (k == "exposure")
    o.exposure = parseFloat(key, v);
  else if (k == "connect")
    o.connect = v;
  else if (k == "window")
    o.window = v;
  else if (k == "token-file")
    o.tokenFile = v;
  else if (k == "server-key")
    o.serverKeyFile = v;
  else if (k == "codec")
    o.codec = v;
  else if (k == "wait")
    o.wait = parseBool(key, v);
  else
    throw CInputError("dfbwall: unknown option '" + k + "'");
}

const char* const kPresets[] = {"cool-warm", "viridis", "grayscale", "inferno", "rainbow"};

template <class T>
std::vector<T> points(const float* data, std::size_t count, const char* what) {
  std::vector<T> out;
  if (count == 0) return out;
  if (!data) throw CInputError(std::string("dfbwall: brick ") + what + " is NULL with a count");
  out.resize(count);
  std::memcpy(out.data(), data, count * sizeof(T));
  return out;
}

dfbwall::Mesh meshOf(const float* positions, std::size_t positionCount,
                     const std::uint32_t* triangles, std::size_t triangleCount, const char* what) {
  dfbwall::Mesh m;
  m.positions = points<dfbwall::Vec3f>(positions, positionCount, what);
  if (triangleCount > 0) {
    if (!triangles) throw CInputError(std::string("dfbwall: brick ") + what + " triangles is NULL");
    m.triangles.resize(triangleCount);
    std::memcpy(m.triangles.data(), triangles, triangleCount * 3 * sizeof(std::uint32_t));
  }
  return m;
}

// A C caller may put any int in an enum; C++ may not load an enum outside its values, so the
// bits are read as an int before they are checked.
template <class Enum>
int enumBits(const Enum& e) {
  static_assert(sizeof(Enum) == sizeof(int));
  int bits;
  std::memcpy(&bits, &e, sizeof bits);
  return bits;
}

dfbwall::Brick brickOf(const dfbwall_brick& c, bool borrowed) {
  dfbwall::Brick b;
  b.id = c.id;
  b.boundsLo = {c.bounds_lo[0], c.bounds_lo[1], c.bounds_lo[2]};
  b.boundsHi = {c.bounds_hi[0], c.bounds_hi[1], c.bounds_hi[2]};
  if (c.volume_count > 0 && !c.volumes)
    throw CInputError("dfbwall: brick " + std::to_string(c.id) + ": volumes is NULL with a count");
  for (std::size_t v = 0; v < c.volume_count; ++v) {
    const dfbwall_volume_part& p = c.volumes[v];
    const int type = enumBits(p.type);
    if (type < DFBWALL_FLOAT32 || type > DFBWALL_FLOAT64)
      throw CInputError("dfbwall: brick " + std::to_string(c.id) + ": volume part " +
                        std::to_string(v) + " has no voxel type " + std::to_string(type));
    dfbwall::VolumePart part;
    part.lo = {p.lo[0], p.lo[1], p.lo[2]};
    part.hi = {p.hi[0], p.hi[1], p.hi[2]};
    part.type = static_cast<dfbwall::VoxelType>(type);  // the same order (static_assert below)
    part.voxels = p.voxels;
    part.borrowed = borrowed;
    b.volumes.push_back(part);
  }
  b.particles.centers = points<dfbwall::Vec3f>(c.particle_centers, c.particle_count, "particles");
  b.particles.radii = points<float>(c.particle_radii, c.radius_count, "particle radii");
  b.ghostParticles.centers =
      points<dfbwall::Vec3f>(c.ghost_particle_centers, c.ghost_particle_count, "ghost particles");
  b.ghostParticles.radii =
      points<float>(c.ghost_particle_radii, c.ghost_radius_count, "ghost particle radii");
  b.mesh = meshOf(c.mesh_positions, c.mesh_position_count, c.mesh_triangles, c.mesh_triangle_count,
                  "mesh");
  b.ghostMesh = meshOf(c.ghost_mesh_positions, c.ghost_mesh_position_count, c.ghost_mesh_triangles,
                       c.ghost_mesh_triangle_count, "ghost mesh");
  return b;
}

static_assert(static_cast<int>(dfbwall::VoxelType::Float32) == DFBWALL_FLOAT32 &&
              static_cast<int>(dfbwall::VoxelType::UInt8) == DFBWALL_UINT8 &&
              static_cast<int>(dfbwall::VoxelType::UInt16) == DFBWALL_UINT16 &&
              static_cast<int>(dfbwall::VoxelType::Int8) == DFBWALL_INT8 &&
              static_cast<int>(dfbwall::VoxelType::Int16) == DFBWALL_INT16 &&
              static_cast<int>(dfbwall::VoxelType::Int32) == DFBWALL_INT32 &&
              static_cast<int>(dfbwall::VoxelType::Float64) == DFBWALL_FLOAT64);
static_assert(sizeof(dfbwall::Vec3f) == 3 * sizeof(float) &&
              sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t));

// Both forms of add_brick: the brick's volume parts copied or borrowed.
dfbwall_error addBrick(dfbwall_session* session, const dfbwall_brick* brick, bool borrowed) {
  return guarded([&] {
    dfbwall::Session& s = sessionOf(session);
    // Refused like a brick that does not fit: at the next frame, on every rank alike.
    dfbwall::Brick b;
    try {
      b = brickOf(need(brick, "the brick"), borrowed);
    } catch (const CInputError& e) {
      s.refuseInput(e.what());
      return;
    }
    s.addBrick(b);
  });
}

}  // namespace

extern "C" {

const char* dfbwall_last_error(void) { return lastMessage.c_str(); }
dfbwall_error dfbwall_last_error_code(void) { return lastCode; }

void dfbwall_set_error_function(dfbwall_error_function function, void* user) {
  std::lock_guard lock(functionMutex);
  errorFunction = function;
  errorUser = user;
}

dfbwall_error dfbwall_options_new(dfbwall_options** out) {
  return guarded([&] { need(out, "out") = new dfbwall_options; });
}

dfbwall_error dfbwall_options_set(dfbwall_options* options, const char* key, const char* value) {
  return guarded([&] {
    setOption(need(options, "the options").options, text(key, "the key"), text(value, "the value"));
  });
}

void dfbwall_options_release(dfbwall_options* options) { delete options; }

dfbwall_error dfbwall_style_new(dfbwall_style** out) {
  return guarded([&] { need(out, "out") = new dfbwall_style; });
}

void dfbwall_style_release(dfbwall_style* style) { delete style; }

dfbwall_error dfbwall_style_add_volume(dfbwall_style* style, const char* name, const int dims[3],
                                       const float origin[3], const float spacing[3], int* index) {
  return guarded([&] {
    dfbwall::Style& st = need(style, "the style").style;
    dfbwall::VolumeStyle v;
    v.name = text(name, "the volume's name");
    if (!dims) throw CInputError("dfbwall: dims is NULL");
    const int* d = dims;
    for (int a = 0; a < 3; ++a)
      if (d[a] < 2)
        throw CInputError("dfbwall: volume '" + v.name + "': dims[" + std::to_string(a) + "] is " +
                          std::to_string(d[a]) + " (at least 2)");
    v.grid.dims = {d[0], d[1], d[2]};
    v.grid.origin = vec(origin, "origin");
    v.grid.spacing = vec(spacing, "spacing");
    st.volumes.push_back(v);
    if (index) *index = static_cast<int>(st.volumes.size()) - 1;
  });
}

dfbwall_error dfbwall_style_set_transfer_function(dfbwall_style* style, int volume,
                                                  const char* preset, float max_opacity) {
  return guarded([&] {
    dfbwall::VolumeStyle& v = volumeOf(style, volume);
    const std::string name = text(preset, "the preset");
    if (std::find(std::begin(kPresets), std::end(kPresets), name) == std::end(kPresets))
      throw CInputError("dfbwall: unknown transfer function preset '" + name +
                        "' (cool-warm, viridis, grayscale, inferno, rainbow)");
    v.transferFunction = name;
    v.maxOpacity = max_opacity;
  });
}

dfbwall_error dfbwall_style_set_value_range(dfbwall_style* style, int volume, float min,
                                            float max) {
  return guarded([&] {
    dfbwall::VolumeStyle& v = volumeOf(style, volume);
    if (!(min < max))
      throw CInputError("dfbwall: value range [" + std::to_string(min) + ", " +
                        std::to_string(max) + "] is empty");
    v.autoRange = false;
    v.valueMin = min;
    v.valueMax = max;
  });
}

dfbwall_error dfbwall_style_set_volume_visible(dfbwall_style* style, int volume, int visible) {
  return guarded([&] { volumeOf(style, volume).visible = visible != 0; });
}

dfbwall_error dfbwall_style_add_isosurface(dfbwall_style* style, int volume, float value,
                                           const float color[3], float opacity) {
  return guarded([&] {
    volumeOf(style, volume);
    style->style.isosurfaces.push_back({volume, value, vec(color, "color"), opacity});
  });
}

dfbwall_error dfbwall_style_add_light(dfbwall_style* style, dfbwall_light_kind kind,
                                      const float direction[3], const float position[3],
                                      const float color[3], float intensity) {
  return guarded([&] {
    dfbwall::Style& st = need(style, "the style").style;
    dfbwall::Light l;
    switch (enumBits(kind)) {
      case DFBWALL_LIGHT_DIRECTIONAL:
        l.kind = dfbwall::Light::Kind::Directional;
        break;
      case DFBWALL_LIGHT_POINT:
        l.kind = dfbwall::Light::Kind::Point;
        break;
      case DFBWALL_LIGHT_AMBIENT:
        l.kind = dfbwall::Light::Kind::Ambient;
        break;
      default:
        throw CInputError("dfbwall: no light kind " + std::to_string(enumBits(kind)));
    }
    if (direction) l.direction = vec(direction, "direction");
    if (position) l.position = vec(position, "position");
    l.color = vec(color, "color");
    l.intensity = intensity;
    st.lights.push_back(l);
  });
}

dfbwall_error dfbwall_style_set_particles(dfbwall_style* style, const float color[3],
                                          float opacity) {
  return guarded([&] {
    need(style, "the style").style.particleColor = vec(color, "color");
    style->style.particleOpacity = opacity;
  });
}

dfbwall_error dfbwall_style_set_mesh(dfbwall_style* style, const float color[3], float opacity) {
  return guarded([&] {
    need(style, "the style").style.meshColor = vec(color, "color");
    style->style.meshOpacity = opacity;
  });
}

dfbwall_error dfbwall_style_set_ambient_occlusion(dfbwall_style* style, int samples,
                                                  float distance) {
  return guarded([&] {
    if (samples < 0 || (samples > 0 && !(distance > 0)))
      throw CInputError("dfbwall: ambient occlusion wants samples >= 0 and a distance > 0");
    need(style, "the style").style.aoSamples = samples;
    style->style.aoDistance = distance;
  });
}

dfbwall_error dfbwall_style_set_shadows(dfbwall_style* style, int on) {
  return guarded([&] { need(style, "the style").style.shadows = on != 0; });
}

dfbwall_error dfbwall_style_set_sampling_rate(dfbwall_style* style, float rate) {
  return guarded([&] {
    if (!(rate > 0)) throw CInputError("dfbwall: the sampling rate must be positive");
    need(style, "the style").style.samplingRate = rate;
  });
}

dfbwall_error dfbwall_style_set_background(dfbwall_style* style, const float color[3]) {
  return guarded([&] { need(style, "the style").style.background = vec(color, "color"); });
}

dfbwall_error dfbwall_style_set_samples_per_pixel(dfbwall_style* style, int spp) {
  return guarded([&] {
    if (spp < 1) throw CInputError("dfbwall: samples per pixel must be at least 1");
    need(style, "the style").style.samplesPerPixel = spp;
  });
}

dfbwall_error dfbwall_style_set_seed(dfbwall_style* style, uint64_t seed) {
  return guarded([&] { need(style, "the style").style.seed = seed; });
}

dfbwall_error dfbwall_session_new(MPI_Comm comm, const dfbwall_options* options,
                                  dfbwall_session** out) {
  return guarded([&] {
    need(out, "out") = nullptr;
    auto handle = std::make_unique<dfbwall_session>();
    handle->session.emplace(comm, options ? options->options : dfbwall::SessionOptions{});
    *out = handle.release();
  });
}

dfbwall_error dfbwall_session_new_f(MPI_Fint comm, const dfbwall_options* options,
                                    dfbwall_session** out) {
  return dfbwall_session_new(MPI_Comm_f2c(comm), options, out);
}

void dfbwall_session_release(dfbwall_session* session) {
  // The destructor waits for nobody and throws nothing (api/DataDistributed.h, "Leaving").
  delete session;
}

int dfbwall_session_is_wall_rank(const dfbwall_session* session) {
  return session && session->session->isWallRank() ? 1 : 0;
}

MPI_Comm dfbwall_session_render_comm(const dfbwall_session* session) {
  return session ? session->session->renderComm() : MPI_COMM_NULL;
}

MPI_Fint dfbwall_session_render_comm_f(const dfbwall_session* session) {
  return MPI_Comm_c2f(dfbwall_session_render_comm(session));
}

int dfbwall_session_canvas_width(const dfbwall_session* session) {
  return session ? session->session->canvasWidth() : 0;
}

int dfbwall_session_canvas_height(const dfbwall_session* session) {
  return session ? session->session->canvasHeight() : 0;
}

dfbwall_error dfbwall_session_run_wall(dfbwall_session* session) {
  return guarded([&] { sessionOf(session).runWall(); });
}

dfbwall_error dfbwall_session_set_style(dfbwall_session* session, const dfbwall_style* style) {
  return guarded([&] { sessionOf(session).setStyle(need(style, "the style").style); });
}

dfbwall_error dfbwall_session_add_brick(dfbwall_session* session, const dfbwall_brick* brick) {
  return addBrick(session, brick, false);
}

dfbwall_error dfbwall_session_add_brick_borrowed(dfbwall_session* session,
                                                 const dfbwall_brick* brick) {
  return addBrick(session, brick, true);
}

dfbwall_error dfbwall_session_data_changed(dfbwall_session* session) {
  return guarded([&] { sessionOf(session).dataChanged(); });
}

dfbwall_error dfbwall_session_clear_bricks(dfbwall_session* session) {
  return guarded([&] { sessionOf(session).clearBricks(); });
}

dfbwall_error dfbwall_session_refuse_input(dfbwall_session* session, const char* why) {
  return guarded([&] { sessionOf(session).refuseInput(text(why, "why")); });
}

dfbwall_error dfbwall_session_set_camera(dfbwall_session* session, const float position[3],
                                         const float look_at[3], const float up[3], float fov_y) {
  return guarded([&] {
    dfbwall::Camera c;
    c.position = vec(position, "position");
    c.lookAt = vec(look_at, "look_at");
    c.up = vec(up, "up");
    c.fovY = fov_y;
    sessionOf(session).setCamera(c);
  });
}

dfbwall_error dfbwall_session_render_frame(dfbwall_session* session) {
  return guarded([&] { sessionOf(session).renderFrame(); });
}

uint32_t dfbwall_session_frames_rendered(const dfbwall_session* session) {
  return session ? session->session->framesRendered() : 0;
}

dfbwall_error dfbwall_session_image(dfbwall_session* session, const uint8_t** pixels, int* width,
                                    int* height) {
  return guarded([&] {
    dfbwall::Session& s = sessionOf(session);
    session->image = s.image();
    const bool have = !session->image.empty();
    need(pixels, "pixels") = have ? session->image.data() : nullptr;
    if (width) *width = have ? s.canvasWidth() : 0;
    if (height) *height = have ? s.canvasHeight() : 0;
  });
}

dfbwall_error dfbwall_session_write_image(dfbwall_session* session, const char* path) {
  return guarded([&] { sessionOf(session).writeImage(text(path, "the path")); });
}

size_t dfbwall_session_scene_bytes(const dfbwall_session* session) {
  return session ? session->session->sceneBytes() : 0;
}

size_t dfbwall_session_borrowed_bytes(const dfbwall_session* session) {
  return session ? session->session->borrowedBytes() : 0;
}

dfbwall_error dfbwall_session_close(dfbwall_session* session) {
  return guarded([&] { sessionOf(session).close(); });
}

}  // extern "C"
