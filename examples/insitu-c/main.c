/* examples/insitu in C, through the C API (<dfbwall/dfbwall.h>, libdfbwall.so): the same
 * heat-equation simulation on an N^3 grid cut into slabs, the same flags, the same pixels.
 *
 *   mpirun -np 6 insitu-c --wall 2x2.toml --capture caps    # 2 simulating ranks, 4 wall ranks
 *   mpirun -np 2 insitu-c --size 400x300 --image last.png   # no wall: the last frame as a PNG
 *   mpirun -np 2 insitu-c --connect wall0:7000 --token-file F
 */
#include <dfbwall/dfbwall.h>
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { kGhost = 1 }; /* planes each side for the stencil (the renderer's: the session's) */

typedef struct Slab {
  int id, z0, z1;
  float *u, *next; /* (z1 - z0 + 2 kGhost) planes of N x N, x fastest */
} Slab;

static void usage(const char* problem) {
  fprintf(stderr,
          "insitu-c: %s\nusage: insitu-c [--grid N] [--blocks B] [--steps S] [--show-every K]\n"
          "              [--wall LAYOUT.toml [--windows] [--capture DIR]]\n"
          "              [--connect HOST:PORT [--token-file F] [--server-key F] [--codec C] "
          "[--wait]\n"
          "               [--window X,Y,W,H|DISPLAY|full] [--capture DIR]]\n"
          "              [--size WxH --image FILE.png] [--threads T]\n",
          problem);
  exit(2);
}

/* Every dfbwall call that fails ends here: the message says what and where. */
static void check(dfbwall_error e) {
  if (e == DFBWALL_OK) return;
  fprintf(stderr, "insitu-c: %s\n", dfbwall_last_error());
  MPI_Abort(MPI_COMM_WORLD, 1);
}

static size_t plane(int n) { return (size_t)n * (size_t)n; }

static float* at(float* f, const Slab* s, int n, int x, int y, int z) {
  return f + ((size_t)(z - s->z0 + kGhost) * (size_t)n + (size_t)y) * (size_t)n + (size_t)x;
}

static float initial(int n, int x, int y, int z) {
  const float h = 2.0f / (float)(n - 1);
  const float px = -1 + h * (float)x, py = -1 + h * (float)y, pz = -1 + h * (float)z;
  const float a = (px - 0.35f) * (px - 0.35f) + py * py + (pz + 0.3f) * (pz + 0.3f);
  const float b =
      (px + 0.4f) * (px + 0.4f) + (py - 0.3f) * (py - 0.3f) + (pz - 0.35f) * (pz - 0.35f);
  return expf(-a / 0.04f) + 0.8f * expf(-b / 0.08f);
}

static int isSource(int n, int x, int y, int z) {
  const int c = n / 2, r = n / 16 > 1 ? n / 16 : 1;
  return abs(x - c) <= r && abs(y - n / 4) <= r && abs(z - c) <= r;
}

static void exchangeGhosts(Slab* mine, int count, int n, int blocks, MPI_Comm comm) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  const size_t ghost = kGhost * plane(n);
  MPI_Request* requests = malloc(sizeof(MPI_Request) * 4 * (size_t)count);
  int used = 0;
  for (int i = 0; i < count; ++i) {
    Slab* s = &mine[i];
    const size_t owned = (size_t)(s->z1 - s->z0);
    if (s->id > 0) {
      const int peer = (s->id - 1) % ranks;
      MPI_Irecv(s->u, (int)ghost, MPI_FLOAT, peer, 2 * s->id, comm, &requests[used++]);
      MPI_Isend(s->u + ghost, (int)ghost, MPI_FLOAT, peer, 2 * (s->id - 1) + 1, comm,
                &requests[used++]);
    }
    if (s->id + 1 < blocks) {
      const int peer = (s->id + 1) % ranks;
      MPI_Irecv(s->u + ghost + owned * plane(n), (int)ghost, MPI_FLOAT, peer, 2 * s->id + 1, comm,
                &requests[used++]);
      MPI_Isend(s->u + owned * plane(n), (int)ghost, MPI_FLOAT, peer, 2 * (s->id + 1), comm,
                &requests[used++]);
    }
  }
  MPI_Waitall(used, requests, MPI_STATUSES_IGNORE);
  free(requests);
}

static void step(Slab* s, int n) {
  const float r = 0.15f;
  const size_t total = (size_t)(s->z1 - s->z0 + 2 * kGhost) * plane(n);
  memcpy(s->next, s->u, total * sizeof(float));
  for (int z = s->z0; z < s->z1; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        float* out = at(s->next, s, n, x, y, z);
        if (x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1) {
          *out = 0;
          continue;
        }
        if (isSource(n, x, y, z)) {
          *out = 1;
          continue;
        }
        const float c = *at(s->u, s, n, x, y, z);
        const float sum = *at(s->u, s, n, x - 1, y, z) + *at(s->u, s, n, x + 1, y, z) +
                          *at(s->u, s, n, x, y - 1, z) + *at(s->u, s, n, x, y + 1, z) +
                          *at(s->u, s, n, x, y, z - 1) + *at(s->u, s, n, x, y, z + 1);
        *out = c + r * (sum - 6 * c);
      }
  float* t = s->u;
  s->u = s->next;
  s->next = t;
}

/* The slab as a brick: clipped to its own planes, its voxels the planes it owns (read by
 * dfbwall_session_add_brick); the session exchanges the ghosts its renderer reads. */
static void addSlab(dfbwall_session* session, const Slab* s, int n) {
  const float h = 2.0f / (float)(n - 1);
  dfbwall_volume_part part = {{0, 0, s->z0}, {n, n, s->z1}, DFBWALL_FLOAT32, NULL};
  part.voxels = s->u + (size_t)kGhost * plane(n);
  dfbwall_brick b = {0};
  b.id = s->id;
  b.bounds_lo[0] = -1, b.bounds_lo[1] = -1, b.bounds_lo[2] = -1 + h * (float)s->z0;
  b.bounds_hi[0] = 1, b.bounds_hi[1] = 1;
  b.bounds_hi[2] = -1 + h * (float)(s->z1 < n - 1 ? s->z1 : n - 1);
  b.volumes = &part;
  b.volume_count = 1;
  b.ghosts = DFBWALL_GHOSTS_EXCHANGE;
  check(dfbwall_session_add_brick(session, &b));
}

static dfbwall_style* makeStyle(int n) {
  dfbwall_style* st = NULL;
  check(dfbwall_style_new(&st));
  const float h = 2.0f / (float)(n - 1);
  const int dims[3] = {n, n, n};
  const float origin[3] = {-1, -1, -1}, spacing[3] = {h, h, h};
  int v = 0;
  check(dfbwall_style_add_volume(st, "temperature", dims, origin, spacing, &v));
  check(dfbwall_style_set_transfer_function(st, v, "inferno", 0.5f));
  check(dfbwall_style_set_value_range(st, v, 0, 1)); /* colours mean one temperature */
  const float blue[3] = {0.3f, 0.6f, 1.0f}, gold[3] = {1.0f, 0.85f, 0.4f};
  check(dfbwall_style_add_isosurface(st, v, 0.1f, blue, 0.3f));
  check(dfbwall_style_add_isosurface(st, v, 0.4f, gold, 1.0f));
  const float background[3] = {0.005f, 0.005f, 0.01f};
  check(dfbwall_style_set_background(st, background));
  check(dfbwall_style_set_seed(st, 7));
  return st;
}

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided);
  int grid = 48, blocks = 4, steps = 40, showEvery = 10;
  const char* image = NULL;
  dfbwall_options* options = NULL;
  check(dfbwall_options_new(&options));
  /* Flags that are session options pass straight through, by the option's own name. */
  static const char* const passed[][2] = {{"--wall", "wall"},
                                          {"--connect", "connect"},
                                          {"--token-file", "token-file"},
                                          {"--server-key", "server-key"},
                                          {"--codec", "codec"},
                                          {"--window", "window"},
                                          {"--capture", "capture"},
                                          {"--threads", "threads"}};
  for (int i = 1; i < argc; ++i) {
    const char* k = argv[i];
    int known = 0;
    if (!strcmp(k, "--wait")) {
      check(dfbwall_options_set(options, "wait", "1"));
      continue;
    }
    if (!strcmp(k, "--windows")) {
      check(dfbwall_options_set(options, "offscreen", "0"));
      continue;
    }
    if (i + 1 >= argc) usage("an option without its value");
    const char* value = argv[++i];
    for (size_t p = 0; p < sizeof passed / sizeof passed[0]; ++p)
      if (!strcmp(k, passed[p][0])) {
        check(dfbwall_options_set(options, passed[p][1], value));
        known = 1;
      }
    if (known) continue;
    if (!strcmp(k, "--grid"))
      grid = atoi(value);
    else if (!strcmp(k, "--blocks"))
      blocks = atoi(value);
    else if (!strcmp(k, "--steps"))
      steps = atoi(value);
    else if (!strcmp(k, "--show-every"))
      showEvery = atoi(value);
    else if (!strcmp(k, "--image"))
      image = value;
    else if (!strcmp(k, "--size")) {
      char width[16], height[16];
      int w = 0, h = 0;
      if (sscanf(value, "%dx%d", &w, &h) != 2) usage("--size wants WxH");
      snprintf(width, sizeof width, "%d", w);
      snprintf(height, sizeof height, "%d", h);
      check(dfbwall_options_set(options, "width", width));
      check(dfbwall_options_set(options, "height", height));
    } else {
      usage("unknown option");
    }
  }
  if (grid < 8 || blocks < 1 || steps < 1 || showEvery < 1) usage("bad numbers");

  dfbwall_session* session = NULL;
  check(dfbwall_session_new(MPI_COMM_WORLD, options, &session));
  dfbwall_options_release(options);
  if (dfbwall_session_is_wall_rank(session)) {
    check(dfbwall_session_run_wall(session)); /* until the simulation's ranks close */
    dfbwall_session_release(session);
    MPI_Finalize();
    return 0;
  }
  MPI_Comm sim = dfbwall_session_render_comm(session);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(sim, &rank);
  MPI_Comm_size(sim, &ranks);
  const int n = grid;
  if (n / blocks < kGhost) {
    if (rank == 0) fprintf(stderr, "insitu-c: slabs under %d planes thick\n", kGhost);
    MPI_Abort(MPI_COMM_WORLD, 2);
  }
  Slab* mine = calloc((size_t)blocks, sizeof(Slab));
  int count = 0;
  for (int b = rank; b < blocks; b += ranks) {
    Slab* s = &mine[count++];
    s->id = b;
    s->z0 = n * b / blocks;
    s->z1 = n * (b + 1) / blocks;
    const size_t total = (size_t)(s->z1 - s->z0 + 2 * kGhost) * plane(n);
    s->u = calloc(total, sizeof(float));
    s->next = calloc(total, sizeof(float));
    for (int z = s->z0; z < s->z1; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) *at(s->u, s, n, x, y, z) = initial(n, x, y, z);
  }
  dfbwall_style* style = makeStyle(n);
  check(dfbwall_session_set_style(session, style));
  dfbwall_style_release(style);
  const float position[3] = {1.7f, 1.2f, -2.0f}, lookAt[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  check(dfbwall_session_set_camera(session, position, lookAt, up, 40));

  exchangeGhosts(mine, count, n, blocks, sim);
  for (int t = 1; t <= steps; ++t) {
    for (int i = 0; i < count; ++i) step(&mine[i], n);
    exchangeGhosts(mine, count, n, blocks, sim);
    if (t % showEvery != 0) continue;
    check(dfbwall_session_clear_bricks(session));
    for (int i = 0; i < count; ++i) addSlab(session, &mine[i], n);
    check(dfbwall_session_render_frame(session));
    if (rank == 0)
      printf("step %d shown (frame %u)\n", t, (unsigned)dfbwall_session_frames_rendered(session));
  }
  if (rank == 0) printf("brick data on rank 0: %zu bytes\n", dfbwall_session_scene_bytes(session));
  if (image) check(dfbwall_session_write_image(session, image));
  check(dfbwall_session_close(session));
  dfbwall_session_release(session);
  for (int i = 0; i < count; ++i) {
    free(mine[i].u);
    free(mine[i].next);
  }
  free(mine);
  MPI_Finalize();
  return 0;
}
