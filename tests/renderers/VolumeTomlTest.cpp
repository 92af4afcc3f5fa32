// [[volumes]] entries and transfer functions from TOML: what a valid entry gives, and errors that
// name file:line:column and the field.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include "base/Error.h"
#include "base/TomlDiagnostics.h"
#include "renderers/scivis/io/VolumeToml.h"
#include "tests/DiagnosticsTestUtil.h"
#include "tests/renderers/VolumeFileTestUtil.h"

namespace renderers::scivis {
namespace {

namespace fs = std::filesystem;

fs::path testDir() {
  const fs::path dir = fs::path(::testing::TempDir()) / "dfbwall-volume-toml-tests";
  fs::create_directories(dir);
  return dir;
}

std::string writeFile(const std::string& name, const std::string& text) {
  const fs::path p = testDir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p.string();
}

// The first [[volumes]] entry of the file; its problems thrown as one base::Error.
VolumeDesc readFirst(const std::string& path) {
  base::TomlDiagnostics diagnostics(path);
  diagnostics.readFile("scene file");
  const std::optional<toml::table> root = diagnostics.parse();
  diagnostics.throwIfAny();
  TomlReader r(diagnostics);
  VolumeDesc d;
  r.entry(
      [&] { d = readVolume(r, *(*root)["volumes"][0].as_table(), fs::path(path).parent_path()); });
  diagnostics.throwIfAny();
  return d;
}

// "(no error)" or the problems reading `text` (saved as `name`) gives, one headline each
// (DiagnosticsTestUtil.h); every message is expected to start with "<path>:".
std::string errorOf(const std::string& name, const std::string& text) {
  const std::string path = writeFile(name, text);
  try {
    readFirst(path);
  } catch (const base::Error& e) {
    const std::string m = testutil::headlines(e.what());
    return m.rfind(path + ":", 0) == 0 ? m.substr(path.size()) : "(no file name) " + m;
  }
  return "(no error)";
}

TEST(VolumeToml, AWaveletEntryGivesItsGridParametersAndTransferFunction) {
  const VolumeDesc d = readFirst(writeFile("wave.toml", R"([[volumes]]
name = "wave"
source = "wavelet"
dims = [65, 33, 17]
sigma = 0.25
z_mag = 7
transfer_function = { preset = "viridis", range = [40, 270], opacity = [[40, 0], [270, 0.4]], opacity_unit = 0.5 }
)"));
  EXPECT_EQ(d.name, "wave");
  EXPECT_TRUE(d.visible);
  EXPECT_EQ(d.source.kind, VolumeSource::Kind::Wavelet);
  EXPECT_EQ(d.source.grid.dims, (Index3{65, 33, 17}));
  // Longest side 2 world units, centred on 0.
  EXPECT_EQ(d.source.grid.spacing, (Vec3{2.0f / 64}));
  EXPECT_EQ(d.source.grid.origin, (Vec3{-1, -0.5f, -0.25f}));
  EXPECT_EQ(d.source.wavelet.sigma, 0.25f);
  EXPECT_EQ(d.source.wavelet.zMag, 7.0f);
  EXPECT_EQ(d.source.wavelet.maximum, 255.0f);  // default
  EXPECT_EQ(d.transfer.valueMin, 40.0f);
  EXPECT_EQ(d.transfer.valueMax, 270.0f);
  EXPECT_EQ(d.transfer.colors.size(), 65u);
  EXPECT_NEAR(d.transfer.opacity(155), 0.2f, 1e-6f);
  EXPECT_EQ(d.transfer.unitDistance, 0.5f);
}

TEST(VolumeToml, DefaultsFollowTheKnownFields) {
  const VolumeDesc w = readFirst(writeFile("defaults.toml", R"([[volumes]]
name = "w"
source = "wavelet"
spacing = [1, 2, 3]
origin = [4, 5, 6]
)"));
  EXPECT_EQ(w.source.grid.dims, (Index3{21, 21, 21}));  // VTK's
  EXPECT_EQ(w.source.grid.spacing, (Vec3{1, 2, 3}));
  EXPECT_EQ(w.source.grid.origin, (Vec3{4, 5, 6}));
  // No transfer function: cool-warm over VTK's range of the field.
  EXPECT_NEAR(w.transfer.valueMin, 37.353f, 1e-3f);
  EXPECT_NEAR(w.transfer.valueMax, 276.829f, 1e-3f);
  EXPECT_NEAR(w.transfer.color(w.transfer.valueMin).x, 0.231373f, 1e-6f);

  const VolumeDesc ml = readFirst(writeFile("ml.toml", R"([[volumes]]
name = "ml"
source = "marschner-lobb"
visible = false
alpha = 0.5
transfer_function = { colors = [[0.2, 1, 0, 0], [0.8, 0, 0, 1]] }
)"));
  EXPECT_EQ(ml.source.grid.dims, (Index3{40, 40, 40}));
  EXPECT_FALSE(ml.visible);
  EXPECT_EQ(ml.source.marschnerLobb.alpha, 0.5f);
  // The field's known range [0, 1] wins over the points' span; opacity: a 0 to 1 ramp.
  EXPECT_EQ(ml.transfer.valueMin, 0.0f);
  EXPECT_EQ(ml.transfer.valueMax, 1.0f);
  EXPECT_EQ(ml.transfer.opacity(0.5f), 0.5f);
}

TEST(VolumeToml, RawFilesResolveAgainstTheSceneFolderAndAreCheckedWhenRead) {
  std::ofstream(testDir() / "ct.raw", std::ios::binary) << std::string(6 + 4 * 3 * 2 * 2, 'x');
  const VolumeDesc d = readFirst(writeFile("raw.toml", R"([[volumes]]
name = "ct"
source = "raw"
file = "ct.raw"
dims = [4, 3, 2]
type = "uint16"
byte_order = "big"
header_bytes = 6
transfer_function = { preset = "grayscale", range = [0, 4096], max_opacity = 0.25 }
)"));
  EXPECT_EQ(d.source.raw.path, (testDir() / "ct.raw").string());
  EXPECT_EQ(d.source.type, VoxelType::UInt16);
  EXPECT_TRUE(d.source.raw.bigEndian);
  EXPECT_EQ(d.source.raw.headerBytes, 6u);
  EXPECT_EQ(d.transfer.opacity(4096), 0.25f);

  const std::string ct = (testDir() / "ct.raw").string();
  EXPECT_EQ(errorOf("raw-size.toml", R"([[volumes]]
name = "ct"
source = "raw"
file = "ct.raw"
dims = [4, 3, 3]
type = "uint16"
header_bytes = 6
transfer_function = { preset = "grayscale", range = [0, 4096] }
)"),
            ":4:8: volume 'ct'.file: " + ct +
                ": raw volume file is 54 bytes, expected 78 bytes (4x3x3 uint16 voxels of 2 bytes "
                "+ 6 header bytes)");
  EXPECT_EQ(errorOf("raw-missing.toml", R"([[volumes]]
name = "ct"
source = "raw"
file = "nothing.raw"
dims = [4, 3, 3]
type = "float32"
transfer_function = { preset = "grayscale", range = [0, 1] }
)"),
            ":4:8: volume 'ct'.file: " + (testDir() / "nothing.raw").string() +
                ": cannot open the raw volume file (No such file or directory); expected 144 bytes "
                "(4x3x3 float32 voxels of 4 bytes + 0 header bytes)");
  const std::string head = "[[volumes]]\nname = \"ct\"\nsource = \"raw\"\nfile = \"ct.raw\"\n";
  EXPECT_EQ(errorOf("raw-nodims.toml", head + "type = \"uint8\"\n"),
            ":1:1: volume 'ct'.dims: missing");
  EXPECT_EQ(errorOf("raw-type.toml", head + "dims = [2, 2, 2]\ntype = \"int8\"\n"),
            ":6:8: volume 'ct'.type: must be \"float32\", \"uint8\" or \"uint16\", not \"int8\"");
  EXPECT_EQ(errorOf("raw-order.toml",
                    head + "dims = [2, 2, 2]\ntype = \"uint8\"\nbyte_order = \"middle\"\n"),
            ":7:14: volume 'ct'.byte_order: must be \"little\" or \"big\", not \"middle\"");
  EXPECT_EQ(
      errorOf("raw-header.toml", head + "dims = [2, 2, 2]\ntype = \"uint8\"\nheader_bytes = -1\n"),
      ":7:16: volume 'ct'.header_bytes: must not be negative, got -1");
  // A file's values are unknown until it is read: a preset needs its range.
  EXPECT_EQ(
      errorOf("raw-norange.toml", head + "dims = [4, 3, 2]\ntype = \"uint16\"\nheader_bytes = 6\n"
                                         "transfer_function = { preset = \"viridis\" }\n"),
      ":8:21: volume 'ct'.transfer_function: missing field 'range' (the volume's values are not "
      "known before reading it)");
  EXPECT_EQ(
      errorOf("raw-notf.toml", head + "dims = [4, 3, 2]\ntype = \"uint16\"\nheader_bytes = 6\n"),
      ":1:1: volume 'ct'.transfer_function: missing");
}

// source = "file": the format from the name (or `format`), the grid from the header, errors
// naming the scene's line and field and the volume file.
TEST(VolumeToml, FilesTakeTheirGridFromTheHeaderAndErrorsNameLineFieldAndFile) {
  const std::string nrrd =
      writeFile("v.nrrd", std::string("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 4 5\n"
                                      "spacings: 2 2 2\nspace origin: (1,2,3)\n\n") +
                              std::string(60, '\7'));
  const std::string head = "[[volumes]]\nname = \"v\"\nsource = \"file\"\n";  // lines 1-3
  const std::string tf = "transfer_function = { preset = \"viridis\", range = [0, 9] }\n";
  const VolumeDesc d = readFirst(writeFile("ok.toml", head + "file = \"v.nrrd\"\n" + tf));
  EXPECT_EQ(d.source.kind, VolumeSource::Kind::File);
  EXPECT_EQ(d.source.grid.dims, (Index3{3, 4, 5}));
  EXPECT_EQ(d.source.grid.spacing, Vec3{2.0f});
  EXPECT_EQ(d.source.grid.origin, (Vec3{1, 2, 3}));
  EXPECT_EQ(d.source.type, VoxelType::UInt8);
  const VolumeDesc moved = readFirst(writeFile(
      "moved.toml", head + "file = \"v.nrrd\"\nspacing = 0.5\norigin = [0, 0, 0]\n" + tf));
  EXPECT_EQ(moved.source.grid.spacing, Vec3{0.5f});
  EXPECT_EQ(moved.source.grid.origin, Vec3{0.0f});
  // .raw files are raw volumes: dims and type then come from the scene.
  writeFile("v.raw", std::string(2 * 3 * 4 * 2, '\0'));
  const VolumeDesc raw = readFirst(
      writeFile("raw.toml", head + "file = \"v.raw\"\ndims = [2, 3, 4]\ntype = \"uint16\"\n" + tf));
  EXPECT_EQ(raw.source.kind, VolumeSource::Kind::RawFile);
  EXPECT_EQ(raw.source.grid.dims, (Index3{2, 3, 4}));
  EXPECT_EQ(
      errorOf("ext.toml", head + "file = \"v.dat\"\n" + tf),
      ":4:8: volume 'v'.file: the format is not known from the name (.nrrd .nhdr .nii .nii.gz "
      ".hdr .mhd .mha .h5 .hdf5 .nc .cdf .vti .pvti); give 'format'");
  EXPECT_EQ(errorOf("fmt.toml", head + "file = \"v.nrrd\"\nformat = \"tiff\"\n" + tf),
            ":5:10: volume 'v'.format: must be \"nrrd\", \"nifti\", \"metaimage\", \"hdf5\", "
            "\"netcdf\" or \"vtk\", not \"tiff\"");
  EXPECT_EQ(errorOf("var.toml", head + "file = \"v.nrrd\"\nvariable = \"T\"\n" + tf),
            ":5:12: volume 'v'.variable: is for NetCDF files");
  EXPECT_EQ(errorOf("array.toml", head + "file = \"v.nrrd\"\narray = \"T\"\n" + tf),
            ":5:9: volume 'v'.array: is for VTK image data (.vti, .pvti)");
  EXPECT_EQ(errorOf("dims.toml", head + "file = \"v.nrrd\"\ndims = [3, 4, 5]\n" + tf),
            ":5:1: volume 'v': unknown field 'dims'; known fields: name, source, origin, spacing, "
            "visible, transfer_function, file, format, dataset, variable, array, time, "
            "time_steps, first_step, fps");
  const std::string nifti =
      errorOf("nifti.toml", head + "file = \"v.nrrd\"\nformat = \"nifti\"\n" + tf);
  EXPECT_EQ(nifti.rfind(":4:8: volume 'v'.file: " + nrrd + ": 146 bytes, too short for a NIfTI", 0),
            0u)
      << nifti;
}

TEST(VolumeToml, ATimeSeriesResolvesEveryStepAndNamesTheStepThatIsWrong) {
  const std::string header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 4 5\n\n";
  for (int k = 0; k < 3; ++k)
    writeFile("s" + std::to_string(10 + k) + ".nrrd", header + std::string(60, char(k)));
  const std::string head = "[[volumes]]\nname = \"s\"\nsource = \"file\"\n";  // lines 1-3
  const std::string tf = "transfer_function = { preset = \"viridis\", range = [0, 9] }\n";
  const VolumeDesc d = readFirst(
      writeFile("series.toml",
                head + "file = \"s%02d.nrrd\"\ntime_steps = 3\nfirst_step = 10\nfps = 4\n" + tf));
  ASSERT_EQ(d.steps.size(), 3u);
  EXPECT_EQ(d.fps, 4.0f);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(d.steps[static_cast<std::size_t>(k)].file.path,
              (testDir() / ("s" + std::to_string(10 + k) + ".nrrd")).string());
    EXPECT_EQ(d.steps[static_cast<std::size_t>(k)].grid.dims, d.source.grid.dims);
    EXPECT_EQ(d.steps[static_cast<std::size_t>(k)].grid.spacing, d.source.grid.spacing);
    EXPECT_EQ(d.steps[static_cast<std::size_t>(k)].grid.origin, d.source.grid.origin);
  }
  EXPECT_EQ(d.source.file.path, d.steps[0].file.path);
  const VolumeDesc glob = readFirst(writeFile("glob.toml", head + "file = \"s1?.nrrd\"\n" + tf));
  ASSERT_EQ(glob.steps.size(), 3u);
  EXPECT_EQ(glob.steps[2].file.path, d.steps[2].file.path);
  EXPECT_EQ(errorOf("nosteps.toml", head + "file = \"s%02d.nrrd\"\n" + tf),
            ":4:8: volume 's'.file: names a pattern of files: give 'time_steps'");
  EXPECT_EQ(errorOf("conv.toml", head + "file = \"s%s.nrrd\"\ntime_steps = 2\n" + tf),
            ":4:8: volume 's'.file: the pattern 's%s.nrrd' has a conversion other than %d, %Nd "
            "or %0Nd (N up to 20) at '%s' (write %% for a '%')");
  EXPECT_EQ(
      errorOf("missing.toml",
              head + "file = \"s%02d.nrrd\"\ntime_steps = 4\nfirst_step = 10\n" + tf)
          .rfind(":4:8: volume 's'.file: time step 3 (" + (testDir() / "s13.nrrd").string() + "): ",
                 0),
      0u);
  EXPECT_EQ(errorOf("fps.toml", head + "file = \"s10.nrrd\"\nfps = 2\n" + tf),
            ":5:7: volume 's'.fps: is for a time series (time_steps, a pattern or a glob)");
  // A 3-D file has no time dimension to step along: step 1 is the error.
  const std::string along =
      errorOf("along.toml", head + "file = \"s10.nrrd\"\ntime_steps = 2\n" + tf);
  EXPECT_EQ(
      along.rfind(
          ":4:8: volume 's'.file: time step 1 (" + (testDir() / "s10.nrrd").string() + "): ", 0),
      0u)
      << along;
  EXPECT_EQ(errorOf("noglob.toml", head + "file = \"none*.nrrd\"\n" + tf),
            ":4:8: volume 's'.file: no file matches '" + (testDir() / "none*.nrrd").string() + "'");
}

TEST(VolumeToml, ASeriesAlongA4dNiftiReadsEachStepOfTheOneFile) {
  // (t, z, y, x) uint8, 3 time steps, step k holding k + 1 everywhere.
  std::string header = volfiletest::niftiHeader(Index3{4, 3, 2}, 2, 8);
  const std::int16_t four = 4, steps = 3;
  std::memcpy(header.data() + 40, &four, 2);
  std::memcpy(header.data() + 48, &steps, 2);
  std::string voxels;
  for (char k = 1; k <= 3; ++k) voxels += std::string(4 * 3 * 2, k);
  const std::string nii = writeFile("t4.nii", header + voxels);
  const std::string head = "[[volumes]]\nname = \"t\"\nsource = \"file\"\nfile = \"t4.nii\"\n";
  const std::string tf = "transfer_function = { preset = \"viridis\", range = [0, 9] }\n";
  const VolumeDesc d =
      readFirst(writeFile("t4.toml", head + "time_steps = 2\nfirst_step = 1\n" + tf));
  ASSERT_EQ(d.steps.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(d.steps[k].file.path, nii);
    EXPECT_EQ(d.steps[k].file.time, static_cast<int>(k) + 1);
    const Volume v = loadVolume(d.steps[k], d.steps[k].grid.wholeBox());
    EXPECT_EQ(v.at(3, 2, 1), static_cast<float>(k + 2)) << "step " << k;
  }
  EXPECT_EQ(readFirst(writeFile("t4-all.toml", head + "time_steps = 3\n" + tf)).steps.size(), 3u);
  const std::string past = errorOf("t4-past.toml", head + "time_steps = 4\n" + tf);
  EXPECT_EQ(past.rfind(":4:8: volume 't'.file: time step 3 (" + nii + "): ", 0), 0u) << past;
  EXPECT_EQ(errorOf("t4-time.toml", head + "time_steps = 2\ntime = 1\n" + tf),
            ":6:8: volume 't'.time: a series along the file's time dimension starts at "
            "'first_step', not 'time'");
}

TEST(VolumeToml, FieldErrorsNameFileLineAndField) {
  const std::string w = "[[volumes]]\nname = \"w\"\nsource = \"wavelet\"\n";  // lines 1-3
  EXPECT_EQ(errorOf("unknown.toml", w + "colour = 1\n"),
            ":4:1: volume 'w': unknown field 'colour'; known fields: name, source, dims, origin, "
            "spacing, visible, transfer_function, maximum, sigma, x_freq, x_mag, y_freq, y_mag, "
            "z_freq, z_mag");
  EXPECT_EQ(errorOf("other-source.toml", w + "f_m = 6\n")
                .rfind(":4:1: volume 'w': unknown field 'f_m'", 0),
            0u);
  EXPECT_EQ(
      errorOf("source.toml", "[[volumes]]\nname = \"w\"\nsource = \"noise\"\n"),
      ":3:10: volume 'w'.source: must be \"wavelet\", \"marschner-lobb\", \"raw\", \"openvdb\" or "
      "\"file\", not \"noise\"");
  EXPECT_EQ(errorOf("dims-small.toml", w + "dims = [64, 1, 64]\n"),
            ":4:13: volume 'w'.dims: must be between 2 and 16384 per axis, not 1");
  EXPECT_EQ(errorOf("dims-big.toml", w + "dims = [25600, 256, 256]\n"),
            ":4:9: volume 'w'.dims: must be between 2 and 16384 per axis, not 25600");
  EXPECT_EQ(errorOf("dims-float.toml", w + "dims = [64, 64.5, 64]\n"),
            ":4:13: volume 'w'.dims: expected an integer, got a floating-point number");
  EXPECT_EQ(errorOf("spacing.toml", w + "spacing = [1, 0, 1]\n"),
            ":4:11: volume 'w'.spacing: must be positive");
  EXPECT_EQ(errorOf("spacing-neg.toml", w + "spacing = -2\n"),
            ":4:11: volume 'w'.spacing: must be positive");
  EXPECT_EQ(errorOf("sigma.toml", w + "sigma = 0\n"), ":4:9: volume 'w'.sigma: must be positive");
  EXPECT_EQ(
      errorOf("alpha.toml", "[[volumes]]\nname = \"m\"\nsource = \"marschner-lobb\"\nalpha = -1\n"),
      ":4:9: volume 'm'.alpha: must not be negative");
  EXPECT_EQ(errorOf("visible.toml", w + "visible = 1\n"),
            ":4:11: volume 'w'.visible: expected true or false, got an integer");
  EXPECT_EQ(errorOf("name.toml", "[[volumes]]\nsource = \"wavelet\"\n"),
            ":1:1: volume.name: missing");
}

TEST(VolumeToml, TransferFunctionErrorsNameFileLineAndField) {
  const std::string w = "[[volumes]]\nname = \"w\"\nsource = \"wavelet\"\n";  // lines 1-3
  const std::string tf = "volume 'w'.transfer_function";
  auto error = [&](const std::string& name, const std::string& table) {
    return errorOf(name, w + "[volumes.transfer_function]\n" + table);  // the table: line 4
  };
  EXPECT_EQ(error("tf-range.toml", "preset = \"viridis\"\nrange = [10, 10]\n"),
            ":6:9: " + tf + ".range: must have low < high");
  EXPECT_EQ(error("tf-range-shape.toml", "preset = \"viridis\"\nrange = [10]\n"),
            ":6:9: " + tf + ".range: expected [low, high] (2 numbers), got 1 element");
  EXPECT_EQ(error("tf-opacity.toml", "preset = \"viridis\"\nopacity = [[0, 0],\n  [10, 1.5]]\n"),
            ":7:3: " + tf + ".opacity: [value, opacity] needs numbers in [0, 1] after the value");
  EXPECT_EQ(error("tf-order.toml", "colors = [[0, 0, 0, 0],\n  [10, 1, 1, 1],\n  [5, 1, 0, 0]]\n"),
            ":7:3: " + tf + ".colors: control point values must be ascending (5 after 10)");
  EXPECT_EQ(error("tf-color-shape.toml", "colors = [[0, 0, 0]]\n"),
            ":5:11: " + tf + ".colors: each point must be [value, r, g, b]");
  EXPECT_EQ(error("tf-color-range.toml", "colors = [[0, 0, 2, 0]]\n"),
            ":5:11: " + tf + ".colors: [value, r, g, b] needs numbers in [0, 1] after the value");
  EXPECT_EQ(error("tf-empty.toml", "opacity = []\npreset = \"viridis\"\n"),
            ":5:11: " + tf + ".opacity: must be a non-empty array of [value, opacity]");
  EXPECT_EQ(error("tf-both.toml", "preset = \"viridis\"\ncolors = [[0, 0, 0, 0]]\n"),
            ":6:10: " + tf + ": give either 'preset' or 'colors', not both");
  EXPECT_EQ(error("tf-none.toml", "opacity = [[0, 0], [1, 1]]\n"),
            ":4:1: " + tf + ": missing field 'preset' or 'colors'");
  EXPECT_EQ(error("tf-preset.toml", "preset = \"jet\"\n"),
            ":5:10: " + tf +
                ".preset: unknown transfer function preset 'jet' (presets: cool-warm, "
                "viridis, inferno, grayscale, rainbow)");
  EXPECT_EQ(error("tf-unknown.toml", "preset = \"viridis\"\ngamma = 2\n"),
            ":6:1: " + tf +
                ": unknown field 'gamma'; known fields: preset, colors, opacity, range, "
                "opacity_unit, max_opacity");
  EXPECT_EQ(error("tf-unit.toml", "preset = \"viridis\"\nopacity_unit = 0\n"),
            ":6:16: " + tf + ".opacity_unit: must be positive");
  EXPECT_EQ(error("tf-max.toml", "preset = \"viridis\"\nmax_opacity = 1.2\n"),
            ":6:15: " + tf + ".max_opacity: must be in [0, 1]");
  EXPECT_EQ(error("tf-max-and-points.toml",
                  "preset = \"viridis\"\nopacity = [[0, 0], [1, 1]]\nmax_opacity = 0.5\n"),
            ":7:15: " + tf +
                ".max_opacity: shapes the default opacity ramp; with 'opacity' given, put "
                "the peak there");
  EXPECT_EQ(errorOf("tf-type.toml", w + "transfer_function = \"viridis\"\n"),
            ":4:21: " + tf + ": expected a table, got a string");
}

}  // namespace
}  // namespace renderers::scivis
