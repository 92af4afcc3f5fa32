#include "renderers/scivis/io/VolumeToml.h"

#include <algorithm>

#include "base/Error.h"
#include "renderers/scivis/io/VolumeSeries.h"
#include "renderers/scivis/io/formats/VolumeFile.h"

namespace renderers::scivis {
namespace {

// Voxels per axis at most. Indices and world positions are floats in the renderer: below 2^14
// voxels a position inside the grid keeps 1/1024 of a voxel of precision (24-bit mantissa), and
// a typo such as 25600 for 256 fails here, naming the line, instead of as an allocation failure
// on every rank.
constexpr int kMaxDims = 16384;

std::string str(float v) {
  std::string s = std::to_string(v);
  s.erase(s.find_last_not_of('0') + 1);
  if (s.back() == '.') s.pop_back();
  return s;
}

Index3 readDims(TomlReader& r, const toml::node& n, const std::string& field) {
  const auto v = r.diagnostics().integers(n, field, 3, "[x, y, z]");
  if (!v) return {};
  const toml::array& a = *n.as_array();
  int d[3] = {};
  for (std::size_t i = 0; i < 3; ++i) {
    if ((*v)[i] < 2 || (*v)[i] > kMaxDims)
      r.problem(a[i], field,
                "must be between 2 and " + std::to_string(kMaxDims) + " per axis, not " +
                    std::to_string((*v)[i]));
    else
      d[i] = static_cast<int>((*v)[i]);
  }
  return {d[0], d[1], d[2]};
}

Vec3 readSpacing(TomlReader& r, const toml::node& n, const std::string& field) {
  const std::size_t before = r.problems();
  const Vec3 s = n.is_array() ? r.vec3(n, field) : Vec3{r.number(n, field)};
  if (r.problems() == before && !(s.x > 0 && s.y > 0 && s.z > 0))
    r.problem(n, field, "must be positive");
  return s;
}

float readInRange(TomlReader& r, const toml::table& t, std::string_view key,
                  const std::string& what, float fallback, float lo, float hi) {
  const float v = r.number(t, key, what, fallback);  // the fallback is in range
  if (v < lo || v > hi)
    r.problem(*t.get(key), what + "." + std::string(key),
              "must be in [" + str(lo) + ", " + str(hi) + "]");
  return v;
}

// [[value, a, b, ...], ...] with `width` numbers per point, values ascending (equal values make a
// step), the other numbers in [0, 1].
template <class Point, class Make>
std::vector<Point> readPoints(TomlReader& r, const toml::node& n, const std::string& field,
                              std::size_t width, const char* shape, Make make) {
  const toml::array* a = n.as_array();
  if (!a || a->empty()) r.fail(n, field, std::string("must be a non-empty array of ") + shape);
  std::vector<Point> points;
  float previous = 0;
  for (const toml::node& p : *a) {
    const toml::array* q = p.as_array();
    if (!q || q->size() != width) {
      r.problem(p, field, std::string("each point must be ") + shape);
      continue;
    }
    const std::size_t before = r.problems();
    float v[4];
    for (std::size_t i = 0; i < width; ++i) v[i] = r.number((*q)[i], field);
    if (r.problems() != before) continue;
    bool inUnit = true;
    for (std::size_t i = 1; i < width; ++i) inUnit = inUnit && v[i] >= 0 && v[i] <= 1;
    if (!inUnit)
      r.problem(p, field, std::string(shape) + " needs numbers in [0, 1] after the value");
    if (!points.empty() && v[0] < previous)
      r.problem(
          p, field,
          "control point values must be ascending (" + str(v[0]) + " after " + str(previous) + ")");
    previous = v[0];
    points.push_back(make(v));
  }
  return points;
}

VolumeSource::Kind readKind(TomlReader& r, const toml::table& t, const std::string& what) {
  const toml::node* n = r.need(t, "source", what);
  const std::string s = r.string(n, what + ".source");
  r.settle();  // without a source, which fields belong to it is unknown
  if (s == "wavelet") return VolumeSource::Kind::Wavelet;
  if (s == "marschner-lobb") return VolumeSource::Kind::MarschnerLobb;
  if (s == "raw") return VolumeSource::Kind::RawFile;
  if (s == "openvdb") return VolumeSource::Kind::OpenVdb;
  if (s == "file") {
    // The existing readers by the file's extension: .raw (with dims and type), .vdb.
    const toml::node* file = t.get("file");
    const std::string name = file && file->is_string() ? *file->value<std::string>() : "";
    const std::string ext = std::filesystem::path(name).extension().string();
    if (ext == ".raw" && !t.get("format")) return VolumeSource::Kind::RawFile;
    if (ext == ".vdb" && !t.get("format")) return VolumeSource::Kind::OpenVdb;
    return VolumeSource::Kind::File;
  }
  r.fail(*n, what + ".source",
         "must be \"wavelet\", \"marschner-lobb\", \"raw\", \"openvdb\" or \"file\", not \"" + s +
             "\"");
}

void readRaw(TomlReader& r, const toml::table& t, const std::string& what,
             const std::filesystem::path& folder, VolumeSource& s) {
  const toml::node* file = r.need(t, "file", what);
  s.raw.path = (folder / r.string(file, what + ".file")).string();
  const toml::node* type = r.need(t, "type", what);
  const std::string typeName = r.string(type, what + ".type");
  if (typeName == "float32")
    s.type = VoxelType::Float32;
  else if (typeName == "uint8")
    s.type = VoxelType::UInt8;
  else if (typeName == "uint16")
    s.type = VoxelType::UInt16;
  else if (type && type->is_string())
    r.problem(*type, what + ".type",
              "must be \"float32\", \"uint8\" or \"uint16\", not \"" + typeName + "\"");
  if (const toml::node* order = t.get("byte_order")) {
    const std::string o = r.string(order, what + ".byte_order");
    if (order->is_string() && o != "little" && o != "big")
      r.problem(*order, what + ".byte_order", "must be \"little\" or \"big\", not \"" + o + "\"");
    s.raw.bigEndian = o == "big";
  }
  if (const toml::node* header = t.get("header_bytes")) {
    const auto v = r.diagnostics().integer(*header, what + ".header_bytes");
    if (v && *v < 0)
      r.problem(*header, what + ".header_bytes", "must not be negative, got " + std::to_string(*v));
    if (v && *v >= 0) s.raw.headerBytes = static_cast<std::uint64_t>(*v);
  }
  r.settle();  // the file is checked against the fields above
  try {
    checkRawFile(s);
  } catch (const base::Error& e) {
    r.fail(*file, what + ".file", e.what());
  }
}

void readOpenVdb(TomlReader& r, const toml::table& t, const std::string& what,
                 const std::filesystem::path& folder, VolumeSource& s) {
  const toml::node* file = r.need(t, "file", what);
  s.vdb.path = (folder / r.string(file, what + ".file")).string();
  if (const toml::node* grid = t.get("grid")) s.vdb.gridName = r.string(grid, what + ".grid");
  r.settle();
  try {
    resolveOpenVdbGrid(s);
  } catch (const base::Error& e) {
    r.fail(*file, what + ".file", e.what());
  }
  for (int a = 0; a < 3; ++a)
    if (s.grid.dims[a] > kMaxDims)
      r.fail(*file, what + ".file",
             "the grid's active voxels span " + std::to_string(s.grid.dims[a]) +
                 " voxels along an axis, more than " + std::to_string(kMaxDims));
}

// A whole number in [lo, hi] from t[key], or `fallback` when absent or wrong (a problem then).
std::int64_t readCount(TomlReader& r, const toml::table& t, std::string_view key,
                       const std::string& what, std::int64_t fallback, std::int64_t lo,
                       std::int64_t hi) {
  const toml::node* n = t.get(key);
  if (!n) return fallback;
  const std::string field = what + "." + std::string(key);
  const auto v = r.diagnostics().integer(*n, field);
  if (!v) return fallback;
  if (*v < lo || *v > hi) {
    r.problem(*n, field,
              "must be from " + std::to_string(lo) + " to " + std::to_string(hi) + ", got " +
                  std::to_string(*v));
    return fallback;
  }
  return *v;
}

std::string dimsText(const Index3& d) {
  return std::to_string(d.x) + "x" + std::to_string(d.y) + "x" + std::to_string(d.z);
}

// A time series' steps (VolumeDesc::steps): step 0 is `s`, resolved by readFile; the others are
// resolved here, each with the grid and type of the first, else an error naming the step's file.
void resolveSteps(TomlReader& r, const toml::node& file, const std::string& what,
                  const VolumeSource& s, const std::vector<std::string>& paths, int firstTime,
                  std::vector<VolumeSource>& steps) {
  const std::size_t count = paths.size();
  steps.reserve(count);
  steps.push_back(s);
  for (std::size_t k = 1; k < count; ++k) {
    VolumeSource step;
    step.kind = VolumeSource::Kind::File;
    step.file.path = paths[k];
    step.file.format = s.file.format;
    step.file.dataset = s.file.dataset;
    step.file.variable = s.file.variable;
    step.file.array = s.file.array;
    step.file.time = paths[k] == paths[0] ? firstTime + static_cast<int>(k) : firstTime;
    const std::string name = "time step " + std::to_string(k) + " (" + paths[k] + ")";
    try {
      resolveVolumeFile(step);
    } catch (const base::Error& e) {
      r.fail(file, what + ".file", name + ": " + e.what());
    }
    if (step.grid.dims != s.grid.dims || step.type != s.type)
      r.fail(file, what + ".file",
             name + " is " + dimsText(step.grid.dims) + " " + voxelTypeName(step.type) +
                 ", the first step (" + paths[0] + ") " + dimsText(s.grid.dims) + " " +
                 voxelTypeName(s.type) + ": every step of a series has the first one's");
    steps.push_back(std::move(step));
  }
}

void readFile(TomlReader& r, const toml::table& t, const std::string& what,
              const std::filesystem::path& folder, VolumeSource& s,
              std::vector<std::string>& series) {
  const toml::node* file = r.need(t, "file", what);
  VolumeFileParams& f = s.file;
  const std::string given = r.string(file, what + ".file");
  f.path = (folder / given).string();
  bool formatKnown = false;
  if (const toml::node* format = t.get("format")) {
    const std::string name = r.string(format, what + ".format");
    const auto named = volumeFormatNamed(name);
    if (named)
      f.format = *named, formatKnown = true;
    else if (format->is_string())
      r.problem(
          *format, what + ".format",
          "must be \"nrrd\", \"nifti\", \"metaimage\", \"hdf5\", \"netcdf\" or \"vtk\", not \"" +
              name + "\"");
  } else if (const auto byName = volumeFormatOfPath(f.path)) {
    f.format = *byName, formatKnown = true;
  } else if (file && file->is_string()) {
    r.problem(*file, what + ".file",
              "the format is not known from the name (.nrrd .nhdr .nii .nii.gz .hdr .mhd .mha .h5 "
              ".hdf5 .nc .cdf .vti .pvti); give 'format'");
  }
  if (const toml::node* d = t.get("dataset")) {
    if (formatKnown && f.format != VolumeFormat::Hdf5)
      r.problem(*d, what + ".dataset", "is for HDF5 files");
    f.dataset = r.string(d, what + ".dataset");
  }
  if (const toml::node* v = t.get("variable")) {
    if (formatKnown && f.format != VolumeFormat::NetCdf)
      r.problem(*v, what + ".variable", "is for NetCDF files");
    f.variable = r.string(v, what + ".variable");
  }
  if (const toml::node* a = t.get("array")) {
    if (formatKnown && f.format != VolumeFormat::Vtk)
      r.problem(*a, what + ".array", "is for VTK image data (.vti, .pvti)");
    f.array = r.string(a, what + ".array");
  }
  f.time = static_cast<int>(readCount(r, t, "time", what, 0, 0, 1 << 30));
  // A time series: a pattern or glob of files, or time_steps along the file's time dimension.
  const SeriesNaming naming = seriesNaming(given);
  const toml::node* steps = t.get("time_steps");
  const toml::node* first = t.get("first_step");
  const auto count = static_cast<std::size_t>(readCount(r, t, "time_steps", what, 1, 1, 100000));
  const auto firstStep = readCount(r, t, "first_step", what, 0, 0, 1 << 30);
  if (naming == SeriesNaming::Pattern && !steps && file)
    r.problem(*file, what + ".file", "names a pattern of files: give 'time_steps'");
  if (naming == SeriesNaming::One && (steps || first) && t.get("time"))
    r.problem(*t.get("time"), what + ".time",
              "a series along the file's time dimension starts at 'first_step', not 'time'");
  const bool isSeries = naming != SeriesNaming::One || steps || first;
  if (const toml::node* fps = t.get("fps"); fps && !isSeries)
    r.problem(*fps, what + ".fps", "is for a time series (time_steps, a pattern or a glob)");
  r.settle();  // the file is read as the fields above say
  try {
    if (naming == SeriesNaming::Pattern) {
      for (std::size_t k = 0; k < count; ++k)
        series.push_back(
            (folder / patternFile(given, static_cast<std::uint64_t>(firstStep) + k)).string());
    } else if (naming == SeriesNaming::Glob) {
      const std::vector<std::string> matches = globFiles((folder / given).string());
      const auto skip = static_cast<std::size_t>(firstStep);
      if (skip >= matches.size())
        throw base::Error("first_step " + std::to_string(skip) + " is past the " +
                          std::to_string(matches.size()) + " files matching '" + given + "'");
      if (steps && skip + count > matches.size())
        throw base::Error("time_steps " + std::to_string(count) + " from first_step " +
                          std::to_string(skip) + " needs more than the " +
                          std::to_string(matches.size()) + " files matching '" + given + "'");
      const std::size_t end = steps ? skip + count : matches.size();
      series.assign(matches.begin() + static_cast<std::ptrdiff_t>(skip),
                    matches.begin() + static_cast<std::ptrdiff_t>(end));
    } else if (isSeries) {
      series.assign(count, f.path);
      f.time = static_cast<int>(firstStep);
    }
  } catch (const base::Error& e) {
    r.fail(*file, what + ".file", e.what());
  }
  if (!series.empty()) f.path = series.front();
  try {
    resolveVolumeFile(s);
  } catch (const base::Error& e) {
    // Point at the field the problem is about: a dataset, variable or time step the file lacks.
    const std::string m =
        series.size() > 1 ? "time step 0 (" + f.path + "): " + e.what() : e.what();
    for (const std::string field : {"dataset", "variable", "array", "time"})
      if (const toml::node* n = t.get(field); n && m.find(" " + field + " ") != std::string::npos)
        r.fail(*n, what + "." + field, m);
    r.fail(*file, what + ".file", m);
  }
}

}  // namespace

TransferFunction readTransferFunction(TomlReader& r, const toml::node& n, const std::string& what) {
  return readTransferFunction(r, n, what, std::nullopt);
}

TransferFunction readTransferFunction(TomlReader& r, const toml::node& n, const std::string& what,
                                      std::optional<std::pair<float, float>> defaultRange) {
  const toml::table* table = r.table(n, what);
  if (!table) r.skip();
  const toml::table& t = *table;
  r.onlyKeys(t, what, {"preset", "colors", "opacity", "range", "opacity_unit", "max_opacity"});
  const toml::node* preset = t.get("preset");
  const toml::node* colors = t.get("colors");
  const toml::node* opacity = t.get("opacity");
  if (preset && colors) r.problem(*colors, what, "give either 'preset' or 'colors', not both");
  if (!preset && !colors) r.problem(t, what, "missing field 'preset' or 'colors'");

  TransferFunction tf;
  if (colors) {
    tf.colors = readPoints<std::pair<float, Vec3>>(r, *colors, what + ".colors", 4,
                                                   "[value, r, g, b]", [](const float* v) {
                                                     return std::pair{v[0], Vec3{v[1], v[2], v[3]}};
                                                   });
  }
  if (opacity) {
    tf.opacities = readPoints<std::pair<float, float>>(r, *opacity, what + ".opacity", 2,
                                                       "[value, opacity]", [](const float* v) {
                                                         return std::pair{v[0], v[1]};
                                                       });
  }

  if (const toml::node* range = t.get("range")) {
    float lohi[2];
    if (r.floats(*range, what + ".range", 2, "[low, high]", lohi)) {
      tf.valueMin = lohi[0];
      tf.valueMax = lohi[1];
      if (!(tf.valueMin < tf.valueMax)) r.problem(*range, what + ".range", "must have low < high");
    }
  } else if (defaultRange) {
    std::tie(tf.valueMin, tf.valueMax) = *defaultRange;
  } else if (colors && !tf.colors.empty()) {
    // The control points span the values they colour.
    tf.valueMin =
        std::min(tf.colors.front().first,
                 tf.opacities.empty() ? tf.colors.front().first : tf.opacities.front().first);
    tf.valueMax =
        std::max(tf.colors.back().first,
                 tf.opacities.empty() ? tf.colors.back().first : tf.opacities.back().first);
    if (!(tf.valueMin < tf.valueMax))
      r.problem(*colors, what, "the control points span no values; give 'range' = [low, high]");
  } else if (!colors) {
    r.problem(t, what,
              "missing field 'range' (the volume's values are not known before reading it)");
  }

  const toml::node* maxOpacity = t.get("max_opacity");
  if (maxOpacity && opacity)
    r.problem(*maxOpacity, what + ".max_opacity",
              "shapes the default opacity ramp; with 'opacity' given, put the peak there");
  const float peak = readInRange(r, t, "max_opacity", what, 1.0f, 0.0f, 1.0f);
  if (const toml::node* unit = t.get("opacity_unit")) {
    const std::size_t before = r.problems();
    tf.unitDistance = r.number(*unit, what + ".opacity_unit");
    if (r.problems() == before && !(tf.unitDistance > 0))
      r.problem(*unit, what + ".opacity_unit", "must be positive");
  }
  r.settle();  // a preset spans the range read above
  if (preset) {
    const std::string name = r.string(*preset, what + ".preset");
    r.settle();
    TransferFunction p;
    try {
      p = transferFunctionPreset(name, tf.valueMin, tf.valueMax, peak);
    } catch (const base::Error& e) {
      r.fail(*preset, what + ".preset", e.what());
    }
    tf.colors = std::move(p.colors);
    if (!opacity) tf.opacities = std::move(p.opacities);
  } else if (!opacity) {
    tf.opacities = {{tf.valueMin, 0.0f}, {tf.valueMax, peak}};
  }
  return tf;
}

VolumeDesc readVolume(TomlReader& r, const toml::table& t, const std::filesystem::path& folder) {
  VolumeDesc d;
  const toml::node* nameNode = r.need(t, "name", "volume");
  d.name = r.string(nameNode, "volume.name");
  const std::string what = nameNode && nameNode->is_string() ? "volume '" + d.name + "'" : "volume";
  VolumeSource& s = d.source;
  s.kind = readKind(r, t, what);
  std::vector<std::string> series;  // a time series' files, step by step
  switch (s.kind) {
    case VolumeSource::Kind::Wavelet:
      r.onlyKeys(t, what,
                 {"name", "source", "dims", "origin", "spacing", "visible", "transfer_function",
                  "maximum", "sigma", "x_freq", "x_mag", "y_freq", "y_mag", "z_freq", "z_mag"});
      break;
    case VolumeSource::Kind::MarschnerLobb:
      r.onlyKeys(t, what,
                 {"name", "source", "dims", "origin", "spacing", "visible", "transfer_function",
                  "f_m", "alpha"});
      break;
    case VolumeSource::Kind::RawFile:
      r.onlyKeys(t, what,
                 {"name", "source", "dims", "origin", "spacing", "visible", "transfer_function",
                  "file", "type", "byte_order", "header_bytes"});
      break;
    case VolumeSource::Kind::OpenVdb:
      r.onlyKeys(
          t, what,
          {"name", "source", "origin", "spacing", "visible", "transfer_function", "file", "grid"});
      break;
    case VolumeSource::Kind::File:
      r.onlyKeys(
          t, what,
          {"name", "source", "origin", "spacing", "visible", "transfer_function", "file", "format",
           "dataset", "variable", "array", "time", "time_steps", "first_step", "fps"});
      break;
  }
  d.visible = r.boolean(t, "visible", what, d.visible);

  // Resolution: VTK's 21³ for the wavelet, Marschner and Lobb's 40³; raw files must say.
  if (const toml::node* dims = t.get("dims"))
    s.grid.dims = readDims(r, *dims, what + ".dims");
  else if (s.kind == VolumeSource::Kind::Wavelet)
    s.grid.dims = {21, 21, 21};
  else if (s.kind == VolumeSource::Kind::MarschnerLobb)
    s.grid.dims = {40, 40, 40};
  else if (s.kind == VolumeSource::Kind::RawFile)
    r.need(t, "dims", what);

  switch (s.kind) {
    case VolumeSource::Kind::Wavelet: {
      WaveletParams& p = s.wavelet;
      p.maximum = r.number(t, "maximum", what, p.maximum);
      p.sigma = r.number(t, "sigma", what, p.sigma);
      if (!(p.sigma > 0)) r.problem(*t.get("sigma"), what + ".sigma", "must be positive");
      p.xFreq = r.number(t, "x_freq", what, p.xFreq);
      p.xMag = r.number(t, "x_mag", what, p.xMag);
      p.yFreq = r.number(t, "y_freq", what, p.yFreq);
      p.yMag = r.number(t, "y_mag", what, p.yMag);
      p.zFreq = r.number(t, "z_freq", what, p.zFreq);
      p.zMag = r.number(t, "z_mag", what, p.zMag);
      break;
    }
    case VolumeSource::Kind::MarschnerLobb:
      s.marschnerLobb.fM = r.number(t, "f_m", what, s.marschnerLobb.fM);
      s.marschnerLobb.alpha = r.number(t, "alpha", what, s.marschnerLobb.alpha);
      if (!(s.marschnerLobb.alpha >= 0))
        r.problem(*t.get("alpha"), what + ".alpha", "must not be negative");
      break;
    case VolumeSource::Kind::RawFile:
      readRaw(r, t, what, folder, s);
      break;
    case VolumeSource::Kind::OpenVdb:
      readOpenVdb(r, t, what, folder, s);
      break;
    case VolumeSource::Kind::File:
      readFile(r, t, what, folder, s, series);
      break;
  }

  // Geometry: the file's own for OpenVDB and files that place their grid, else the longest side
  // 2 world units centred on 0; either can be overridden.
  const Index3 n = s.grid.dims;
  const bool fileGeometry = s.kind == VolumeSource::Kind::OpenVdb ||
                            (s.kind == VolumeSource::Kind::File && s.file.hasGeometry);
  const toml::node* spacing = t.get("spacing");
  const toml::node* origin = t.get("origin");
  if (spacing) s.grid.spacing = readSpacing(r, *spacing, what + ".spacing");
  if (origin) s.grid.origin = r.vec3(*origin, what + ".origin");
  r.settle();  // the defaults below and the checks after them judge the fields above
  if (!spacing && !fileGeometry)
    s.grid.spacing = Vec3{2.0f / static_cast<float>(std::max({n.x, n.y, n.z}) - 1)};
  if (!origin && !fileGeometry)
    s.grid.origin = {-0.5f * s.grid.spacing.x * static_cast<float>(n.x - 1),
                     -0.5f * s.grid.spacing.y * static_cast<float>(n.y - 1),
                     -0.5f * s.grid.spacing.z * static_cast<float>(n.z - 1)};

  // Every step of a series has the first one's grid (and its own file's voxels).
  if (!series.empty()) {
    resolveSteps(r, *t.get("file"), what, s, series, s.file.time, d.steps);
    for (VolumeSource& step : d.steps) step.grid = s.grid;
    if (const toml::node* fps = t.get("fps")) {
      d.fps = r.number(*fps, what + ".fps");
      if (!(d.fps >= 0 && d.fps <= 1000)) r.problem(*fps, what + ".fps", "must be in [0, 1000]");
    }
  }

  // Where its size was given (a brick's memory budget names it), and whether float can place
  // its voxels.
  const toml::node* sized = t.get("dims") ? t.get("dims") : t.get("file");
  d.where = r.where(sized ? *sized : t, what + (sized ? (t.get("dims") ? ".dims" : ".file") : ""));
  if (const std::string problem = s.grid.problem(); !problem.empty()) {
    const std::size_t space = problem.find(' ');  // "spacing along x, ...": the field first
    r.fail(spacing  ? *spacing
           : origin ? *origin
                    : t,
           what + "." + problem.substr(0, space), problem.substr(space + 1));
  }

  // Procedural fields know their range, so a preset needs none; files do not (unless invisible,
  // when the transfer function is never used). The wavelet's range costs evaluations: only
  // when the transfer function does not give one.
  const toml::node* tf = t.get("transfer_function");
  const bool rangeGiven = tf && tf->is_table() && tf->as_table()->get("range");
  const std::optional<std::pair<float, float>> range =
      rangeGiven ? std::nullopt : knownValueRange(s);
  if (tf) {
    d.transfer = readTransferFunction(r, *tf, what + ".transfer_function", range);
  } else if (range) {
    d.transfer = transferFunctionPreset("cool-warm", range->first, range->second);
  } else if (d.visible) {
    r.need(t, "transfer_function", what);
  }
  return d;
}

}  // namespace renderers::scivis
