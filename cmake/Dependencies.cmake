# Every dependency comes from a Debian package; when one is missing, say which package to install
# (scripts/setup installs them all).
function(dfbwall_missing what package)
  message(FATAL_ERROR "dfbwall: ${what} not found. Install the Debian package '${package}' "
                      "(apt-get install ${package}), or run scripts/setup, which installs everything.")
endfunction()

macro(dfbwall_find_package name package)
  find_package(${name} ${ARGN} QUIET)
  if(NOT ${name}_FOUND)
    dfbwall_missing(${name} ${package})
  endif()
endmacro()

# A pkg-config module as the imported target PkgConfig::<prefix> (a macro: <prefix>_FOUND and
# the other results stay in the caller's scope, as pkg_check_modules leaves them).
macro(dfbwall_pkg_module prefix module what package)
  pkg_check_modules(${prefix} QUIET IMPORTED_TARGET ${module})
  if(NOT ${prefix}_FOUND)
    dfbwall_missing("${what} (pkg-config module ${module})" ${package})
  endif()
endmacro()

# The C bindings only: the CXX component drags in the deprecated libmpi_cxx.
dfbwall_find_package(MPI "libopenmpi-dev and openmpi-bin" COMPONENTS C)
dfbwall_find_package(Snappy libsnappy-dev CONFIG)
dfbwall_find_package(TBB libtbb-dev COMPONENTS tbb)
dfbwall_find_package(PNG libpng-dev)
dfbwall_find_package(tomlplusplus libtomlplusplus-dev 3)
dfbwall_find_package(CLI11 libcli11-dev CONFIG)
dfbwall_find_package(nlohmann_json nlohmann-json3-dev 3 CONFIG)
dfbwall_find_package(embree libembree-dev 3)
dfbwall_find_package(assimp libassimp-dev)
# OpenVDB volumes. Not through the FindOpenVDB.cmake that libopenvdb-dev ships: it insists on
# Boost.Iostreams (which the package does not pull in) and comes with its own FindTBB.cmake that
# would shadow oneTBB's config for the whole project. The library needs only itself, oneTBB and
# Imath (its half type) on the link line.
find_path(OPENVDB_INCLUDE_DIR openvdb/openvdb.h)
find_library(OPENVDB_LIBRARY openvdb)
if(NOT OPENVDB_INCLUDE_DIR OR NOT OPENVDB_LIBRARY)
  dfbwall_missing(OpenVDB libopenvdb-dev)
endif()
dfbwall_find_package(Imath libimath-dev CONFIG)
add_library(OpenVDB::openvdb UNKNOWN IMPORTED)
set_target_properties(OpenVDB::openvdb PROPERTIES
  IMPORTED_LOCATION ${OPENVDB_LIBRARY}
  INTERFACE_INCLUDE_DIRECTORIES ${OPENVDB_INCLUDE_DIR}
  INTERFACE_LINK_LIBRARIES "TBB::tbb;Imath::Imath")
# Wall presenters. The OpenGL lookup only checks the GL headers are there: no wall library links
# libGL (GLFW loads it itself; the OSMesa presenter must not see it, see wall/CMakeLists.txt).
dfbwall_find_package(glfw3 libglfw3-dev 3.3)
set(OpenGL_GL_PREFERENCE GLVND)
dfbwall_find_package(OpenGL libgl-dev)
dfbwall_find_package(X11 libx11-dev)  # the GLFW presenter reads its window back; libgl-dev pulls it in
dfbwall_find_package(PkgConfig pkg-config)
dfbwall_pkg_module(OSMESA osmesa "OSMesa" libosmesa6-dev)
# The control server (apps/ControlServer.cpp): Debian's libmicrohttpd, an event-loop HTTP server
# with connection caps (docs/security.md, "The control API", says why not cpp-httplib).
dfbwall_pkg_module(MICROHTTPD libmicrohttpd "libmicrohttpd" libmicrohttpd-dev)
# Volume files (renderers/scivis/io/formats/): serial HDF5 (what Debian's NetCDF links; each rank
# opens the file itself and reads its hyperslab), NetCDF, zlib for gzip-compressed NRRD/NIfTI,
# bzip2 for NRRD; VTK image data (.vti/.pvti): expat for the XML, zlib and LZ4 for its blocks.
dfbwall_pkg_module(HDF5 hdf5-serial "HDF5" libhdf5-dev)
dfbwall_pkg_module(NETCDF netcdf "NetCDF" libnetcdf-dev)
dfbwall_find_package(ZLIB zlib1g-dev)
dfbwall_find_package(BZip2 libbz2-dev)
dfbwall_find_package(EXPAT libexpat1-dev)
dfbwall_pkg_module(LZ4 liblz4 "LZ4" liblz4-dev)
if(DFBWALL_BUILD_TESTS)
  dfbwall_find_package(GTest libgtest-dev)
endif()

if(NOT MPIEXEC_EXECUTABLE)
  dfbwall_missing(mpiexec openmpi-bin)
endif()
# The wall service (wall/service/): ZeroMQ for the links between render jobs and the wall,
# libjpeg-turbo's TurboJPEG for the lossy codec, FreeType for the idle screens' text.
dfbwall_pkg_module(ZMQ libzmq "ZeroMQ" libzmq3-dev)
dfbwall_pkg_module(TURBOJPEG libturbojpeg "TurboJPEG" libturbojpeg0-dev)
dfbwall_pkg_module(FREETYPE freetype2 "FreeType" libfreetype-dev)
# The wall service's credentials (wall/service/security/): a CURVE key pair derived from the token,
# constant-time comparisons, random tokens.
dfbwall_pkg_module(SODIUM libsodium "libsodium" libsodium-dev)
