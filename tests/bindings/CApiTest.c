/* The C API's errors on 3 real ranks, compiled as C99 against the header a C program includes:
 * every failure is a code, the thread's last message and a call of the error function, never an
 * exception or an abort; bad input on one rank is DFBWALL_ERROR_INPUT at the next frame on every
 * rank, after which the session renders; a call out of order is DFBWALL_ERROR_USAGE; the image
 * is there on render rank 0; borrowed voxels render the copy's image without a copy held, and
 * values changed in place show after dfbwall_session_data_changed. Exits non-zero on any rank
 * whose checks failed. */
#include <dfbwall/dfbwall.h>
#include <mpi.h>
#include <stdio.h>
#include <string.h>

static int failures = 0;
static int rank = 0;

#define CHECK(cond)                                                                             \
  do {                                                                                          \
    if (!(cond)) {                                                                              \
      fprintf(stderr, "rank %d: %s:%d: %s (last error: %s)\n", rank, __FILE__, __LINE__, #cond, \
              dfbwall_last_error());                                                            \
      ++failures;                                                                               \
    }                                                                                           \
  } while (0)

static int calls = 0;
static dfbwall_error lastCalled = DFBWALL_OK;
static char lastMessage[512];

static void onError(void* user, dfbwall_error code, const char* message) {
  ++*(int*)user;
  lastCalled = code;
  snprintf(lastMessage, sizeof lastMessage, "%s", message);
}

static int contains(const char* text, const char* part) { return strstr(text, part) != NULL; }

enum { kN = 12 };
static float field[kN][kN][kN]; /* [z][y][x] */

static dfbwall_error addPart(dfbwall_session* s, dfbwall_voxel_type type, int borrowed) {
  dfbwall_volume_part part = {{0, 0, 0}, {kN, kN, kN}, DFBWALL_FLOAT32, NULL};
  part.type = type;
  part.voxels = field;
  dfbwall_brick b = {0};
  b.id = 0;
  b.bounds_hi[0] = b.bounds_hi[1] = b.bounds_hi[2] = kN - 1;
  b.volumes = &part;
  b.volume_count = 1;
  return borrowed ? dfbwall_session_add_brick_borrowed(s, &b) : dfbwall_session_add_brick(s, &b);
}

static dfbwall_error addWhole(dfbwall_session* s, dfbwall_voxel_type type) {
  return addPart(s, type, 0);
}

/* Render rank 0's image of the next frame into `into` (elsewhere nothing). */
static void frameInto(dfbwall_session* s, uint8_t* into, size_t bytes) {
  CHECK(dfbwall_session_render_frame(s) == DFBWALL_OK);
  const uint8_t* pixels = NULL;
  CHECK(dfbwall_session_image(s, &pixels, NULL, NULL) == DFBWALL_OK);
  if (pixels) memcpy(into, pixels, bytes);
}

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) field[z][y][x] = (float)(x * y + z) / (kN * kN);
  dfbwall_set_error_function(onError, &calls);

  /* Options: an unknown name and a value that does not parse, each named. */
  dfbwall_options* o = NULL;
  CHECK(dfbwall_options_new(&o) == DFBWALL_OK);
  CHECK(dfbwall_options_set(o, "widht", "64") == DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "unknown option 'widht'"));
  CHECK(calls == 1 && lastCalled == DFBWALL_ERROR_INPUT);
  CHECK(strcmp(lastMessage, dfbwall_last_error()) == 0);
  CHECK(dfbwall_options_set(o, "height", "tall") == DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "height") && contains(dfbwall_last_error(), "tall"));
  CHECK(dfbwall_last_error_code() == DFBWALL_ERROR_INPUT);
  CHECK(dfbwall_options_set(o, "width", "64") == DFBWALL_OK);
  CHECK(dfbwall_options_set(o, "height", "48") == DFBWALL_OK);
  CHECK(dfbwall_options_set(o, "tile-size", "16") == DFBWALL_OK);
  CHECK(dfbwall_options_set(o, "threads", "1") == DFBWALL_OK);
  CHECK(dfbwall_options_set(o, "timeout", "60") == DFBWALL_OK);

  /* No communicator, no handle. */
  dfbwall_session* s = NULL;
  CHECK(dfbwall_session_new(MPI_COMM_NULL, o, &s) == DFBWALL_ERROR_INPUT && s == NULL);
  CHECK(contains(dfbwall_last_error(), "MPI_COMM_NULL"));
  CHECK(dfbwall_session_render_frame(NULL) == DFBWALL_ERROR_INPUT);

  /* The communicator as a Fortran handle (the Fortran module's way in) and back. */
  CHECK(dfbwall_session_new_f(MPI_Comm_c2f(MPI_COMM_WORLD), o, &s) == DFBWALL_OK);
  dfbwall_options_release(o);
  CHECK(!dfbwall_session_is_wall_rank(s));
  int same = MPI_UNEQUAL;
  MPI_Comm_compare(MPI_Comm_f2c(dfbwall_session_render_comm_f(s)), MPI_COMM_WORLD, &same);
  CHECK(same == MPI_CONGRUENT);
  CHECK(dfbwall_session_canvas_width(s) == 64 && dfbwall_session_canvas_height(s) == 48);

  /* A frame before any style: a call out of order, on every rank. */
  CHECK(dfbwall_session_render_frame(s) == DFBWALL_ERROR_USAGE);
  CHECK(contains(dfbwall_last_error(), "before setStyle()"));

  dfbwall_style* st = NULL;
  CHECK(dfbwall_style_new(&st) == DFBWALL_OK);
  const int dims[3] = {kN, kN, kN};
  const float origin[3] = {0, 0, 0}, spacing[3] = {1, 1, 1};
  int v = -1;
  CHECK(dfbwall_style_add_volume(st, "f", dims, origin, spacing, &v) == DFBWALL_OK && v == 0);
  CHECK(dfbwall_style_set_transfer_function(st, 0, "plasma", 0.5f) == DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "'plasma'"));
  CHECK(dfbwall_style_set_transfer_function(st, 1, "viridis", 0.5f) == DFBWALL_ERROR_INPUT);
  CHECK(dfbwall_style_set_transfer_function(st, 0, "viridis", 0.5f) == DFBWALL_OK);
  CHECK(dfbwall_style_set_value_range(st, 0, 0, 1) == DFBWALL_OK);
  const float white[3] = {1, 1, 1};
  CHECK(dfbwall_style_add_isosurface(st, 0, 0.5f, white, 1) == DFBWALL_OK);
  const float down[3] = {0, -1, 0};
  CHECK(dfbwall_style_add_light(st, (dfbwall_light_kind)7, down, NULL, white, 1) ==
        DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "no light kind 7"));
  CHECK(dfbwall_session_set_style(s, st) == DFBWALL_OK);
  dfbwall_style_release(st);
  const float position[3] = {20, 16, -18}, at[3] = {5.5f, 5.5f, 5.5f}, up[3] = {0, 1, 0};
  CHECK(dfbwall_session_set_camera(s, position, at, up, 40) == DFBWALL_OK);

  /* Rank 1 gives a voxel type that does not exist: refused at the next frame, on every rank. */
  CHECK(dfbwall_session_clear_bricks(s) == DFBWALL_OK);
  if (rank == 0) CHECK(addWhole(s, DFBWALL_FLOAT32) == DFBWALL_OK);
  if (rank == 1) CHECK(addWhole(s, (dfbwall_voxel_type)42) == DFBWALL_OK);
  const int before = calls;
  CHECK(dfbwall_session_render_frame(s) == DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "render rank 1 refused its input"));
  CHECK(contains(dfbwall_last_error(), "no voxel type 42"));
  CHECK(calls == before + 1);
  CHECK(dfbwall_session_frames_rendered(s) == 0);

  /* A binding's own check failed on rank 2: refused at the next frame, on every rank. */
  if (rank == 0) CHECK(addWhole(s, DFBWALL_FLOAT32) == DFBWALL_OK);
  if (rank == 2)
    CHECK(dfbwall_session_refuse_input(s, "the array is not contiguous") == DFBWALL_OK);
  CHECK(dfbwall_session_render_frame(s) == DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "render rank 2 refused its input"));
  CHECK(contains(dfbwall_last_error(), "the array is not contiguous"));
  CHECK(dfbwall_session_refuse_input(s, NULL) == DFBWALL_ERROR_INPUT);
  CHECK(dfbwall_session_frames_rendered(s) == 0);

  /* Corrected: the session renders, and rank 0 has the image. */
  if (rank == 0) CHECK(addWhole(s, DFBWALL_FLOAT32) == DFBWALL_OK);
  CHECK(dfbwall_session_render_frame(s) == DFBWALL_OK);
  CHECK(dfbwall_session_frames_rendered(s) == 1);
  const uint8_t* pixels = NULL;
  int w = -1, h = -1;
  CHECK(dfbwall_session_image(s, &pixels, &w, &h) == DFBWALL_OK);
  if (rank == 0) {
    CHECK(pixels != NULL && w == 64 && h == 48);
    int bright = 0;
    for (int i = 0; pixels && i < w * h; ++i) bright += pixels[4 * i] > 60;
    CHECK(bright > 50); /* the isosurface is there, not a blank */
  } else {
    CHECK(pixels == NULL && w == 0 && h == 0);
  }
  /* Rank 0 holds the voxels (and what the renderer derives from them); the others nothing. */
  if (rank == 0) CHECK(dfbwall_session_scene_bytes(s) >= sizeof field);
  if (rank != 0) CHECK(dfbwall_session_scene_bytes(s) == 0);
  CHECK(dfbwall_session_borrowed_bytes(s) == 0);

  /* Borrowed voxels: the copy's image, with no copy held. */
  static uint8_t copied[64 * 48 * 4], borrowed[64 * 48 * 4], changed[64 * 48 * 4];
  if (rank == 0 && pixels) memcpy(copied, pixels, sizeof copied);
  const size_t held = dfbwall_session_scene_bytes(s);
  CHECK(dfbwall_session_clear_bricks(s) == DFBWALL_OK);
  if (rank == 0) CHECK(addPart(s, DFBWALL_FLOAT32, 1) == DFBWALL_OK);
  frameInto(s, borrowed, sizeof borrowed);
  if (rank == 0) {
    CHECK(memcmp(borrowed, copied, sizeof copied) == 0);
    CHECK(dfbwall_session_borrowed_bytes(s) == sizeof field);
    CHECK(dfbwall_session_scene_bytes(s) + sizeof field <= held);
  }
  /* int16 voxels are converted, so they cannot be borrowed: refused on every rank. */
  CHECK(dfbwall_session_clear_bricks(s) == DFBWALL_OK);
  if (rank == 2) CHECK(addPart(s, DFBWALL_INT16, 1) == DFBWALL_OK);
  CHECK(dfbwall_session_render_frame(s) == DFBWALL_ERROR_INPUT);
  CHECK(contains(dfbwall_last_error(), "render rank 2 refused its input") &&
        contains(dfbwall_last_error(), "borrowed voxels must be float32"));
  if (rank == 0) CHECK(addPart(s, DFBWALL_FLOAT32, 1) == DFBWALL_OK);
  frameInto(s, borrowed, sizeof borrowed);
  /* The program changes the values in place and says so: the next frame shows them, as a fresh
   * copy of them renders. */
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) field[z][y][x] = 1.0f - field[z][y][x] * field[z][y][x];
  if (rank == 0) CHECK(dfbwall_session_data_changed(s) == DFBWALL_OK);
  frameInto(s, changed, sizeof changed);
  if (rank == 0) CHECK(memcmp(changed, borrowed, sizeof changed) != 0);
  CHECK(dfbwall_session_clear_bricks(s) == DFBWALL_OK);
  if (rank == 0) CHECK(addWhole(s, DFBWALL_FLOAT32) == DFBWALL_OK);
  frameInto(s, copied, sizeof copied);
  if (rank == 0) CHECK(memcmp(changed, copied, sizeof copied) == 0);
  CHECK(dfbwall_session_close(s) == DFBWALL_OK);
  dfbwall_session_release(s);

  int total = 0;
  MPI_Allreduce(&failures, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0) printf("%s: %d failed checks\n", total ? "FAIL" : "PASS", total);
  MPI_Finalize();
  return failures ? 1 : 0;
}
