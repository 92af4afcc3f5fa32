/* dfbwall's C API: the data-distributed API (<dfbwall/DataDistributed.h>, docs/insitu.md) for C,
 * Fortran (through iso_c_binding) and any language that calls C. One shared library,
 * libdfbwall.so, carries every C++ dependency inside and exports only the dfbwall_* functions: a
 * simulation links it and MPI.
 *
 * Handles are opaque: a session (dfbwall_session) and a style (dfbwall_style). Every call that
 * can fail returns a dfbwall_error; DFBWALL_OK is 0. No C++ exception crosses this API. The
 * message of the last failed call on this thread is dfbwall_last_error(); an error function set
 * with dfbwall_set_error_function() is also called with every failure, on the failing thread.
 *
 * The ranks, the scene versions, which calls are collective, and what every error means on the
 * other ranks are the C++ API's (its header's comments): in short, with a wall layout the last W
 * ranks of the communicator call dfbwall_session_run_wall(); the others simulate on
 * dfbwall_session_render_comm(), add their bricks, and call dfbwall_session_render_frame() once
 * per frame. Bad input is DFBWALL_ERROR_INPUT at the next render_frame on every render rank
 * alike (the session stays usable: give the input again); DFBWALL_ERROR_FAILED leaves it
 * unusable. dfbwall_session_close() is the collective way out; dfbwall_session_release() of a
 * session not closed waits for nobody, and the other ranks' next call fails at once naming it.
 *
 * MPI must be initialised with MPI_THREAD_MULTIPLE. C99. */
#ifndef DFBWALL_H
#define DFBWALL_H

#include <mpi.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(__GNUC__)
#define DFBWALL_API __attribute__((visibility("default")))
#else
#define DFBWALL_API
#endif

typedef enum dfbwall_error {
  DFBWALL_OK = 0,
  DFBWALL_ERROR_INPUT = 1,  /* bad input: a null or unknown argument, a refused brick, ... */
  DFBWALL_ERROR_USAGE = 2,  /* a call out of order or on the wrong rank (before set_style, ...) */
  DFBWALL_ERROR_FAILED = 3, /* a rank failed, left or stopped answering: the session is unusable */
  DFBWALL_ERROR_OUT_OF_MEMORY = 4,
  DFBWALL_ERROR_UNKNOWN = 5
} dfbwall_error;

/* The message of the last call on this thread that failed ("" when none did). Valid until the
 * thread's next failing call. */
DFBWALL_API const char* dfbwall_last_error(void);
DFBWALL_API dfbwall_error dfbwall_last_error_code(void);
/* Called with every failure, on the failing thread, after dfbwall_last_error() is set; NULL
 * removes it. Process-wide. */
typedef void (*dfbwall_error_function)(void* user, dfbwall_error code, const char* message);
DFBWALL_API void dfbwall_set_error_function(dfbwall_error_function function, void* user);

/* ---- Session options: key and value as text, as dfbwall's command-line options say them. ----
 * Keys: "width", "height" (without a wall), "wall" (a layout TOML), "offscreen" ("1"/"0"),
 * "capture" (a folder), "capture-every", "tile-size", "threads", "frames-in-flight", "timeout"
 * (seconds), "exposure", "connect" (HOST:PORT of `dfbwall serve`), "window" ("X,Y,W,H", a
 * display or "full"), "token-file", "server-key", "codec", "wait" ("1"/"0"). An unknown key or
 * a value that does not parse is DFBWALL_ERROR_INPUT naming it. */
typedef struct dfbwall_options dfbwall_options;
DFBWALL_API dfbwall_error dfbwall_options_new(dfbwall_options** out);
DFBWALL_API dfbwall_error dfbwall_options_set(dfbwall_options* options, const char* key,
                                              const char* value);
DFBWALL_API void dfbwall_options_release(dfbwall_options* options);

/* ---- Style: everything but the data, the same on every render rank. ---- */
typedef struct dfbwall_style dfbwall_style;
typedef enum dfbwall_light_kind {
  DFBWALL_LIGHT_DIRECTIONAL = 0,
  DFBWALL_LIGHT_POINT = 1,
  DFBWALL_LIGHT_AMBIENT = 2
} dfbwall_light_kind;

DFBWALL_API dfbwall_error dfbwall_style_new(dfbwall_style** out);
DFBWALL_API void dfbwall_style_release(dfbwall_style* style);
/* A volume of `dims` voxels, voxel (i,j,k) at origin + spacing * (i,j,k); its index (0, 1, ...)
 * in *index when index is not NULL. Its transfer function is "cool-warm" over the voxels' range
 * until set. */
DFBWALL_API dfbwall_error dfbwall_style_add_volume(dfbwall_style* style, const char* name,
                                                   const int dims[3], const float origin[3],
                                                   const float spacing[3], int* index);
/* A preset: "cool-warm", "viridis", "grayscale", "inferno" or "rainbow"; opacity rises from 0 to
 * max_opacity over the range. */
DFBWALL_API dfbwall_error dfbwall_style_set_transfer_function(dfbwall_style* style, int volume,
                                                              const char* preset,
                                                              float max_opacity);
/* A fixed value range (colours mean the same value in every frame); without one, the range of
 * the voxels all ranks hold at each scene version. */
DFBWALL_API dfbwall_error dfbwall_style_set_value_range(dfbwall_style* style, int volume, float min,
                                                        float max);
DFBWALL_API dfbwall_error dfbwall_style_set_volume_visible(dfbwall_style* style, int volume,
                                                           int visible);
DFBWALL_API dfbwall_error dfbwall_style_add_isosurface(dfbwall_style* style, int volume,
                                                       float value, const float color[3],
                                                       float opacity);
/* No light added: an ambient light and a headlight. direction: the way the light travels. */
DFBWALL_API dfbwall_error dfbwall_style_add_light(dfbwall_style* style, dfbwall_light_kind kind,
                                                  const float direction[3], const float position[3],
                                                  const float color[3], float intensity);
DFBWALL_API dfbwall_error dfbwall_style_set_particles(dfbwall_style* style, const float color[3],
                                                      float opacity);
DFBWALL_API dfbwall_error dfbwall_style_set_mesh(dfbwall_style* style, const float color[3],
                                                 float opacity);
DFBWALL_API dfbwall_error dfbwall_style_set_ambient_occlusion(dfbwall_style* style, int samples,
                                                              float distance);
DFBWALL_API dfbwall_error dfbwall_style_set_shadows(dfbwall_style* style, int on);
DFBWALL_API dfbwall_error dfbwall_style_set_sampling_rate(dfbwall_style* style, float rate);
DFBWALL_API dfbwall_error dfbwall_style_set_background(dfbwall_style* style, const float color[3]);
DFBWALL_API dfbwall_error dfbwall_style_set_samples_per_pixel(dfbwall_style* style, int spp);
DFBWALL_API dfbwall_error dfbwall_style_set_seed(dfbwall_style* style, uint64_t seed);

/* ---- Bricks: what one rank holds, read (copied) by dfbwall_session_add_brick; its voxels
 * borrowed (read in place) by dfbwall_session_add_brick_borrowed. ---- */
typedef enum dfbwall_voxel_type {
  DFBWALL_FLOAT32 = 0, /* float32, uint8, uint16: held as given */
  DFBWALL_UINT8 = 1,
  DFBWALL_UINT16 = 2,
  DFBWALL_INT8 = 3, /* int8, int16, int32, float64: converted to float32 */
  DFBWALL_INT16 = 4,
  DFBWALL_INT32 = 5,
  DFBWALL_FLOAT64 = 6
} dfbwall_voxel_type;

/* A brick's part of one volume: voxels [lo, hi) of the whole field, x fastest, then y, then z
 * (lo == hi: none of this volume). */
typedef struct dfbwall_volume_part {
  int lo[3], hi[3];
  dfbwall_voxel_type type;
  const void* voxels;
} dfbwall_volume_part;

/* Start from dfbwall_brick b = {0}: every array is optional (count 0). Points are 3 floats each,
 * triangles 3 indices each; radii: 1 for all particles or one per particle. Ghost particles and
 * triangles are seen by shading rays only. */
typedef struct dfbwall_brick {
  int id;                             /* >= 0; the same id on two ranks: the same data */
  float bounds_lo[3], bounds_hi[3];   /* camera rays are clipped to these bounds */
  const dfbwall_volume_part* volumes; /* one per style volume, or none */
  size_t volume_count;
  const float* particle_centers;
  size_t particle_count;
  const float* particle_radii;
  size_t radius_count;
  const float* ghost_particle_centers;
  size_t ghost_particle_count;
  const float* ghost_particle_radii;
  size_t ghost_radius_count;
  const float* mesh_positions;
  size_t mesh_position_count;
  const uint32_t* mesh_triangles;
  size_t mesh_triangle_count;
  const float* ghost_mesh_positions;
  size_t ghost_mesh_position_count;
  const uint32_t* ghost_mesh_triangles;
  size_t ghost_mesh_triangle_count;
} dfbwall_brick;

/* ---- Session ---- */
typedef struct dfbwall_session dfbwall_session;

/* Collective over comm (duplicated, not kept). options may be NULL (an 800x600 image). */
DFBWALL_API dfbwall_error dfbwall_session_new(MPI_Comm comm, const dfbwall_options* options,
                                              dfbwall_session** out);
/* dfbwall_session_new for Fortran and other languages that hold MPI handles as MPI_Fint: the old
 * `mpi` module's integer or mpi_f08's MPI_Comm%MPI_VAL (converted with MPI_Comm_f2c). */
DFBWALL_API dfbwall_error dfbwall_session_new_f(MPI_Fint comm, const dfbwall_options* options,
                                                dfbwall_session** out);
/* Not collective: without dfbwall_session_close() before, the session leaves (the others fail at
 * once, naming this rank). NULL is allowed. */
DFBWALL_API void dfbwall_session_release(dfbwall_session* session);
DFBWALL_API int dfbwall_session_is_wall_rank(const dfbwall_session* session);
/* The render ranks' communicator (MPI_COMM_NULL on wall ranks): simulate on it. */
DFBWALL_API MPI_Comm dfbwall_session_render_comm(const dfbwall_session* session);
/* The same as an MPI_Fint (MPI_Comm_c2f): the Fortran handle of the render ranks' communicator. */
DFBWALL_API MPI_Fint dfbwall_session_render_comm_f(const dfbwall_session* session);
DFBWALL_API int dfbwall_session_canvas_width(const dfbwall_session* session);
DFBWALL_API int dfbwall_session_canvas_height(const dfbwall_session* session);
/* Wall ranks: presents frames until the render ranks close the session. */
DFBWALL_API dfbwall_error dfbwall_session_run_wall(dfbwall_session* session);

DFBWALL_API dfbwall_error dfbwall_session_set_style(dfbwall_session* session,
                                                    const dfbwall_style* style);
DFBWALL_API dfbwall_error dfbwall_session_add_brick(dfbwall_session* session,
                                                    const dfbwall_brick* brick);
/* The brick with its volumes' voxels borrowed, not copied (its particles and triangles are
 * copied): float32, uint8 or uint16, aligned to their size (other types are
 * DFBWALL_ERROR_INPUT at the next frame, on every rank). The program keeps the voxels alive and
 * unchanged while the session holds the brick: until the render_frame that replaces its bricks
 * (the first after clear_bricks or a new add_brick that returns DFBWALL_OK), or close or
 * release. It may change their values between frames, never during render_frame, and then calls
 * dfbwall_session_data_changed before the next frame (until then frames read the new values
 * through structures built from the old ones: stale, never outside the brick). */
DFBWALL_API dfbwall_error dfbwall_session_add_brick_borrowed(dfbwall_session* session,
                                                             const dfbwall_brick* brick);
/* The program changed borrowed voxels: the next render_frame takes the value ranges again,
 * rebuilds what depends on the values (macrocells, isosurfaces) and starts averaging afresh. */
DFBWALL_API dfbwall_error dfbwall_session_data_changed(dfbwall_session* session);
DFBWALL_API dfbwall_error dfbwall_session_clear_bricks(dfbwall_session* session);
/* A binding's own check of the program's input failed on this rank (a Fortran array that is not
 * contiguous, ...): refused like a brick that does not fit, by the next render_frame on every
 * render rank alike, with `why` as the message. */
DFBWALL_API dfbwall_error dfbwall_session_refuse_input(dfbwall_session* session, const char* why);
/* Render rank 0's camera is the one used. fov_y in degrees. */
DFBWALL_API dfbwall_error dfbwall_session_set_camera(dfbwall_session* session,
                                                     const float position[3],
                                                     const float look_at[3], const float up[3],
                                                     float fov_y);
DFBWALL_API dfbwall_error dfbwall_session_render_frame(dfbwall_session* session);
DFBWALL_API uint32_t dfbwall_session_frames_rendered(const dfbwall_session* session);
/* Render rank 0 without a wall: the last frame, RGBA8, rows top to bottom, width x height
 * pixels, valid until the session's next call; elsewhere *pixels is NULL and the size 0. */
DFBWALL_API dfbwall_error dfbwall_session_image(dfbwall_session* session, const uint8_t** pixels,
                                                int* width, int* height);
/* Render rank 0 without a wall: the last frame as a PNG; elsewhere nothing. */
DFBWALL_API dfbwall_error dfbwall_session_write_image(dfbwall_session* session, const char* path);
/* The bytes of brick data this rank holds in the current scene version (borrowed voxels not
 * counted), and the bytes of borrowed voxels it reads in place. */
DFBWALL_API size_t dfbwall_session_scene_bytes(const dfbwall_session* session);
DFBWALL_API size_t dfbwall_session_borrowed_bytes(const dfbwall_session* session);
/* Render ranks, collective with run_wall returning on the wall ranks. */
DFBWALL_API dfbwall_error dfbwall_session_close(dfbwall_session* session);

#ifdef __cplusplus
}
#endif

#endif /* DFBWALL_H */
