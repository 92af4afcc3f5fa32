// The Python module `dfbwall` (pybind11) over the data-distributed API: a Session on an mpi4py
// communicator, the style as a dict, bricks from numpy arrays (voxels borrowed where their dtype
// is one the renderer holds), the image as a numpy array. Errors are Python exceptions:
// dfbwall.InputError (a ValueError) for input the session refused, at the next render_frame() on
// every rank alike; RuntimeError for the rest.
#include <mpi.h>
#include <mpi4py/mpi4py.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cstring>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "api/DataDistributed.h"

namespace py = pybind11;

namespace {

MPI_Comm commOf(const py::handle& comm) {
  MPI_Comm* c = PyMPIComm_Get(comm.ptr());
  if (!c) throw py::error_already_set();
  return *c;
}

dfbwall::Vec3f vec3(const py::handle& v, const char* what) {
  const auto values = v.cast<std::vector<float>>();
  if (values.size() != 3)
    throw dfbwall::InputError(std::string("dfbwall: ") + what + " wants 3 numbers, not " +
                              std::to_string(values.size()));
  return {values[0], values[1], values[2]};
}

// The keys a dict may have: any other is refused by name (a typo must not pass silently).
void onlyKeys(const py::dict& d, std::initializer_list<const char*> keys, const char* what) {
  for (const auto& item : d) {
    const std::string k = py::str(item.first);
    bool known = false;
    for (const char* key : keys) known = known || k == key;
    if (!known)
      throw dfbwall::InputError(std::string("dfbwall: ") + what + ": unknown key '" + k + "'");
  }
}

template <class T>
void take(const py::dict& d, const char* key, T& into) {
  if (d.contains(key)) into = d[key].cast<T>();
}

void takeVec(const py::dict& d, const char* key, dfbwall::Vec3f& into) {
  if (d.contains(key)) into = vec3(d[key], key);
}

dfbwall::Style styleOf(const py::dict& d) {
  onlyKeys(d,
           {"volumes", "isosurfaces", "lights", "particle_color", "particle_opacity", "mesh_color",
            "mesh_opacity", "ao_samples", "ao_distance", "shadows", "sampling_rate", "background",
            "samples_per_pixel", "seed"},
           "style");
  dfbwall::Style st;
  if (d.contains("volumes"))
    for (const auto& item : d["volumes"]) {
      const auto v = item.cast<py::dict>();
      onlyKeys(v,
               {"name", "dims", "origin", "spacing", "transfer_function", "max_opacity", "range",
                "visible"},
               "style volume");
      dfbwall::VolumeStyle vs;
      take(v, "name", vs.name);
      if (v.contains("dims")) {
        const auto dims = v["dims"].cast<std::vector<int>>();
        if (dims.size() != 3)
          throw dfbwall::InputError("dfbwall: style volume dims wants 3 numbers");
        vs.grid.dims = {dims[0], dims[1], dims[2]};
      }
      takeVec(v, "origin", vs.grid.origin);
      takeVec(v, "spacing", vs.grid.spacing);
      take(v, "transfer_function", vs.transferFunction);
      take(v, "max_opacity", vs.maxOpacity);
      take(v, "visible", vs.visible);
      if (v.contains("range") && !v["range"].is_none()) {
        const auto range = v["range"].cast<std::vector<float>>();
        if (range.size() != 2)
          throw dfbwall::InputError("dfbwall: style volume range wants 2 numbers");
        vs.autoRange = false;
        vs.valueMin = range[0];
        vs.valueMax = range[1];
      }
      st.volumes.push_back(vs);
    }
  if (d.contains("isosurfaces"))
    for (const auto& item : d["isosurfaces"]) {
      const auto i = item.cast<py::dict>();
      onlyKeys(i, {"volume", "value", "color", "opacity"}, "style isosurface");
      dfbwall::Isosurface iso;
      take(i, "volume", iso.volume);
      take(i, "value", iso.value);
      takeVec(i, "color", iso.color);
      take(i, "opacity", iso.opacity);
      st.isosurfaces.push_back(iso);
    }
  if (d.contains("lights"))
    for (const auto& item : d["lights"]) {
      const auto l = item.cast<py::dict>();
      onlyKeys(l, {"kind", "direction", "position", "color", "intensity"}, "style light");
      dfbwall::Light light;
      std::string kind = "directional";
      take(l, "kind", kind);
      if (kind == "directional")
        light.kind = dfbwall::Light::Kind::Directional;
      else if (kind == "point")
        light.kind = dfbwall::Light::Kind::Point;
      else if (kind == "ambient")
        light.kind = dfbwall::Light::Kind::Ambient;
      else
        throw dfbwall::InputError("dfbwall: style light kind '" + kind +
                                  "' (directional, point, ambient)");
      takeVec(l, "direction", light.direction);
      takeVec(l, "position", light.position);
      takeVec(l, "color", light.color);
      take(l, "intensity", light.intensity);
      st.lights.push_back(light);
    }
  takeVec(d, "particle_color", st.particleColor);
  take(d, "particle_opacity", st.particleOpacity);
  takeVec(d, "mesh_color", st.meshColor);
  take(d, "mesh_opacity", st.meshOpacity);
  take(d, "ao_samples", st.aoSamples);
  take(d, "ao_distance", st.aoDistance);
  take(d, "shadows", st.shadows);
  take(d, "sampling_rate", st.samplingRate);
  takeVec(d, "background", st.background);
  take(d, "samples_per_pixel", st.samplesPerPixel);
  take(d, "seed", st.seed);
  return st;
}

std::optional<dfbwall::VoxelType> voxelTypeOf(const py::dtype& t) {
  if (t.is(py::dtype::of<float>())) return dfbwall::VoxelType::Float32;
  if (t.is(py::dtype::of<std::uint8_t>())) return dfbwall::VoxelType::UInt8;
  if (t.is(py::dtype::of<std::uint16_t>())) return dfbwall::VoxelType::UInt16;
  if (t.is(py::dtype::of<std::int8_t>())) return dfbwall::VoxelType::Int8;
  if (t.is(py::dtype::of<std::int16_t>())) return dfbwall::VoxelType::Int16;
  if (t.is(py::dtype::of<std::int32_t>())) return dfbwall::VoxelType::Int32;
  if (t.is(py::dtype::of<double>())) return dfbwall::VoxelType::Float64;
  // Equal but not the same object (a dtype made from a string): compare by value.
  const char* names[] = {"float32", "uint8", "uint16", "int8", "int16", "int32", "float64"};
  const std::string name = py::str(t.attr("name"));
  for (int i = 0; i < 7; ++i)
    if (name == names[i] && t.attr("isnative").cast<bool>())
      return static_cast<dfbwall::VoxelType>(i);
  return std::nullopt;
}

// The session's hold on a numpy array it borrows voxels from: released (under the GIL, from
// whichever thread drops the brick) when the session no longer holds the brick.
std::shared_ptr<const void> keepAlive(const py::array& array) {
  auto* held = new py::object(array);
  return std::shared_ptr<const void>(held->ptr(), [held](const void*) {
    py::gil_scoped_acquire gil;
    delete held;
  });
}

// A numpy array of N points: shape (N, 3), float32, C order (converted when it is not).
std::vector<dfbwall::Vec3f> pointsOf(const py::handle& a, const char* what) {
  auto arr = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!arr || arr.ndim() != 2 || arr.shape(1) != 3)
    throw dfbwall::InputError(std::string("dfbwall: ") + what + " wants an array of shape (N, 3)");
  std::vector<dfbwall::Vec3f> out(static_cast<std::size_t>(arr.shape(0)));
  std::memcpy(out.data(), arr.data(), out.size() * sizeof(dfbwall::Vec3f));
  return out;
}

class PySession {
 public:
  PySession(const py::object& comm, const dfbwall::SessionOptions& options) {
    const MPI_Comm c = comm.is_none() ? MPI_COMM_NULL : commOf(comm);
    {
      py::gil_scoped_release release;
      session_.emplace(c, options);
    }
    live().insert(this);
  }

  PySession(const PySession&) = delete;
  PySession& operator=(const PySession&) = delete;
  ~PySession() { live().erase(this); }

  dfbwall::Session& s() {
    if (!session_) throw std::logic_error("dfbwall: the session was released");
    return *session_;
  }
  // Drops the session: not collective; without close() before, it leaves (the others fail at
  // once, naming this rank).
  void release() {
    py::gil_scoped_release unlocked;
    session_.reset();
  }
  // Sessions still alive when Python exits are released before mpi4py finalises MPI.
  static std::set<PySession*>& live() {
    static std::set<PySession*> sessions;
    return sessions;
  }

  py::object renderComm() {
    const MPI_Comm c = s().renderComm();
    if (c == MPI_COMM_NULL) return py::none();
    // A view of the session's communicator: mpi4py does not free it.
    return py::reinterpret_steal<py::object>(PyMPIComm_New(c));
  }

  // A brick from numpy arrays. Whatever does not fit (a dtype, a shape) is refused by the next
  // render_frame() on every rank alike, as the C++ API refuses a brick outside its field. Voxel
  // arrays of float32, uint8 or uint16 are borrowed (unless `copy`): read in place, the array
  // held by the session as long as it holds the brick; the other dtypes are converted (copied).
  void addBrick(int id, const py::object& lo, const py::object& hi, const py::list& volumes,
                const py::object& particles, const py::object& radii,
                const py::object& ghostParticles, const py::object& ghostRadii,
                const py::object& positions, const py::object& triangles, bool copy) {
    dfbwall::Session& session = s();
    dfbwall::Brick b;
    b.id = id;
    std::vector<py::array> keep;  // the arrays read below, alive until addBrick has copied them
    try {
      b.boundsLo = vec3(lo, "bounds_lo");
      b.boundsHi = vec3(hi, "bounds_hi");
      for (const auto& item : volumes) {
        const auto part = item.cast<py::tuple>();
        if (part.size() != 2)
          throw dfbwall::InputError("dfbwall: brick " + std::to_string(id) +
                                    ": a volume part is (lo, array)");
        const auto at = part[0].cast<std::vector<int>>();
        if (!py::isinstance<py::array>(part[1]))
          throw dfbwall::InputError("dfbwall: brick " + std::to_string(id) +
                                    ": a volume's voxels must be a numpy array");
        auto arr = part[1].cast<py::array>();
        const auto type = voxelTypeOf(arr.dtype());
        if (!type)
          throw dfbwall::InputError(
              "dfbwall: brick " + std::to_string(id) + ": voxels of dtype " +
              std::string(py::str(arr.dtype())) +
              " (float32, uint8, uint16, int8, int16, int32 or float64, native byte order)");
        if (arr.ndim() != 3 || at.size() != 3)
          throw dfbwall::InputError("dfbwall: brick " + std::to_string(id) +
                                    ": voxels must be a 3-D array indexed [z, y, x], lo (x, y, z)");
        if (!(arr.flags() & py::array::c_style))
          throw dfbwall::InputError("dfbwall: brick " + std::to_string(id) +
                                    ": voxels must be C-contiguous (numpy.ascontiguousarray)");
        dfbwall::VolumePart p;
        p.lo = {at[0], at[1], at[2]};
        p.hi = {at[0] + static_cast<int>(arr.shape(2)), at[1] + static_cast<int>(arr.shape(1)),
                at[2] + static_cast<int>(arr.shape(0))};
        p.type = *type;
        p.voxels = arr.data();  // read in place (no copy here)
        const bool held = *type == dfbwall::VoxelType::Float32 ||
                          *type == dfbwall::VoxelType::UInt8 || *type == dfbwall::VoxelType::UInt16;
        if (!copy && held && (arr.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_)) {
          p.borrowed = true;
          p.owner = keepAlive(arr);
        }
        b.volumes.push_back(p);
        keep.push_back(arr);
      }
      if (!particles.is_none()) b.particles.centers = pointsOf(particles, "particles");
      if (!radii.is_none()) b.particles.radii = radii.cast<std::vector<float>>();
      if (!ghostParticles.is_none())
        b.ghostParticles.centers = pointsOf(ghostParticles, "ghost_particles");
      if (!ghostRadii.is_none()) b.ghostParticles.radii = ghostRadii.cast<std::vector<float>>();
      if (!positions.is_none()) b.mesh.positions = pointsOf(positions, "positions");
      if (!triangles.is_none()) {
        auto t = py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>::ensure(
            triangles);
        if (!t || t.ndim() != 2 || t.shape(1) != 3)
          throw dfbwall::InputError("dfbwall: triangles wants an array of shape (N, 3)");
        b.mesh.triangles.resize(static_cast<std::size_t>(t.shape(0)));
        std::memcpy(b.mesh.triangles.data(), t.data(), b.mesh.triangles.size() * 12);
      }
    } catch (const dfbwall::InputError& e) {
      session.refuseInput(e.what());
      return;
    } catch (const py::cast_error& e) {
      session.refuseInput("dfbwall: brick " + std::to_string(id) + ": " + e.what());
      return;
    }
    session.addBrick(b);
  }

  py::object image() {
    std::vector<std::uint8_t> pixels = s().image();
    if (pixels.empty()) return py::none();
    const auto h = static_cast<py::ssize_t>(s().canvasHeight());
    const auto w = static_cast<py::ssize_t>(s().canvasWidth());
    py::array_t<std::uint8_t> out({h, w, py::ssize_t{4}});
    std::memcpy(out.mutable_data(), pixels.data(), pixels.size());
    return out;
  }

 private:
  std::optional<dfbwall::Session> session_;
};

}  // namespace

PYBIND11_MODULE(dfbwall, m) {
  if (import_mpi4py() < 0) throw py::error_already_set();
  m.doc() = "dfbwall's data-distributed API: simulations show their data on a display wall";
  py::register_exception<dfbwall::InputError>(m, "InputError", PyExc_ValueError);

  py::class_<PySession>(m, "Session")
      .def(py::init([](const py::object& comm, int width, int height, const std::string& wall,
                       bool offscreen, const std::string& capture, int captureEvery, int tileSize,
                       int threads, int framesInFlight, int timeout, float exposure,
                       const std::string& connect, const std::string& window,
                       const std::string& tokenFile, const std::string& serverKey,
                       const std::string& codec, bool wait) {
             dfbwall::SessionOptions o;
             o.width = width, o.height = height, o.wall = wall, o.offscreen = offscreen;
             o.captureDir = capture, o.captureEvery = captureEvery, o.tileSize = tileSize;
             o.threads = threads, o.framesInFlight = framesInFlight, o.timeoutSeconds = timeout;
             o.exposure = exposure, o.connect = connect, o.window = window;
             o.tokenFile = tokenFile, o.serverKeyFile = serverKey, o.codec = codec, o.wait = wait;
             return std::make_unique<PySession>(comm, o);
           }),
           py::arg("comm"), py::kw_only(), py::arg("width") = 800, py::arg("height") = 600,
           py::arg("wall") = "", py::arg("offscreen") = true, py::arg("capture") = "",
           py::arg("capture_every") = 0, py::arg("tile_size") = 64, py::arg("threads") = 0,
           py::arg("frames_in_flight") = 2, py::arg("timeout") = 300, py::arg("exposure") = 1.0f,
           py::arg("connect") = "", py::arg("window") = "", py::arg("token_file") = "",
           py::arg("server_key") = "", py::arg("codec") = "snappy", py::arg("wait") = false)
      .def_property_readonly("is_wall_rank", [](PySession& p) { return p.s().isWallRank(); })
      .def_property_readonly("render_comm", &PySession::renderComm)
      .def_property_readonly("canvas_width", [](PySession& p) { return p.s().canvasWidth(); })
      .def_property_readonly("canvas_height", [](PySession& p) { return p.s().canvasHeight(); })
      .def_property_readonly("frames_rendered", [](PySession& p) { return p.s().framesRendered(); })
      .def_property_readonly("scene_bytes", [](PySession& p) { return p.s().sceneBytes(); })
      .def_property_readonly("borrowed_bytes", [](PySession& p) { return p.s().borrowedBytes(); })
      .def(
          "run_wall", [](PySession& p) { p.s().runWall(); },
          py::call_guard<py::gil_scoped_release>())
      .def(
          "set_style", [](PySession& p, const py::dict& style) { p.s().setStyle(styleOf(style)); },
          py::arg("style"))
      .def("add_brick", &PySession::addBrick, py::arg("id"), py::arg("bounds_lo"),
           py::arg("bounds_hi"), py::kw_only(), py::arg("volumes") = py::list(),
           py::arg("particles") = py::none(), py::arg("radii") = py::none(),
           py::arg("ghost_particles") = py::none(), py::arg("ghost_radii") = py::none(),
           py::arg("positions") = py::none(), py::arg("triangles") = py::none(),
           py::arg("copy") = false)
      .def("data_changed", [](PySession& p) { p.s().dataChanged(); })
      .def("clear_bricks", [](PySession& p) { p.s().clearBricks(); })
      .def(
          "set_camera",
          [](PySession& p, const py::object& position, const py::object& lookAt,
             const py::object& up, float fovY) {
            dfbwall::Camera c;
            c.position = vec3(position, "position");
            c.lookAt = vec3(lookAt, "look_at");
            c.up = vec3(up, "up");
            c.fovY = fovY;
            p.s().setCamera(c);
          },
          py::arg("position"), py::arg("look_at") = py::make_tuple(0, 0, 0),
          py::arg("up") = py::make_tuple(0, 1, 0), py::arg("fov_y") = 45.0f)
      .def(
          "render_frame", [](PySession& p) { p.s().renderFrame(); },
          py::call_guard<py::gil_scoped_release>())
      .def("image", &PySession::image)
      .def(
          "write_image", [](PySession& p, const std::string& path) { p.s().writeImage(path); },
          py::call_guard<py::gil_scoped_release>())
      .def(
          "close", [](PySession& p) { p.s().close(); }, py::call_guard<py::gil_scoped_release>())
      .def("release", &PySession::release)
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__",
           [](PySession& p, const py::object& type, const py::object&, const py::object&) {
             // Without an exception the collective close(); with one, the session leaves when it is
             // released (the other ranks fail at once, naming this one).
             if (type.is_none() && !p.s().isWallRank()) {
               py::gil_scoped_release release;
               p.s().close();
             } else if (!type.is_none()) {
               p.release();
             }
             return false;
           });
  // After mpi4py's own handler (registered when it was imported, before this module): Python's
  // exit handlers run last-registered first, so MPI is still up here.
  py::module_::import("atexit").attr("register")(py::cpp_function([] {
    for (PySession* p : std::set<PySession*>(PySession::live())) p->release();
  }));
}
