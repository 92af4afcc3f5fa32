/* The in-situ frame of bench/insitu_languages.py from C (the C API, libdfbwall.so): the frame of
 * InsituFrameBench.cpp, call for call, its JSON line with "language": "c".
 *   mpirun -np R insitu_frame_bench_c GRID FRAMES WIDTHxHEIGHT IMAGE.png */
#include <dfbwall/dfbwall.h>
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double nowMs(void) { return MPI_Wtime() * 1e3; }

static int check(dfbwall_error e) {
  if (e != DFBWALL_OK) {
    fprintf(stderr, "%s\n", dfbwall_last_error());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  return 0;
}

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided);
  int width = 0, height = 0;
  if (argc != 5 || sscanf(argv[3], "%dx%d", &width, &height) != 2) {
    fprintf(stderr, "usage: insitu_frame_bench_c GRID FRAMES WxH IMAGE\n");
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  const int g = atoi(argv[1]), frames = atoi(argv[2]);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const int z0 = (g - 1) * rank / ranks, z1 = (g - 1) * (rank + 1) / ranks;
  const int lo = z0 - 2 > 0 ? z0 - 2 : 0, hi = z1 + 4 < g ? z1 + 4 : g;
  float* u = malloc((size_t)(hi - lo) * (size_t)g * (size_t)g * sizeof(float));
  double* ms = malloc((size_t)frames * sizeof(double));
  double* cpu = malloc((size_t)frames * sizeof(double));
  double* calls = malloc((size_t)frames * sizeof(double));
  if (!u || !ms || !cpu || !calls) MPI_Abort(MPI_COMM_WORLD, 1);
  const double c = (g - 1) / 2.0;
  size_t n = 0;
  for (int z = lo; z < hi; ++z)
    for (int y = 0; y < g; ++y)
      for (int x = 0; x < g; ++x)
        u[n++] = (float)(((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c)) / (3 * c * c));

  dfbwall_options* o = NULL;
  check(dfbwall_options_new(&o));
  char size[32];
  snprintf(size, sizeof size, "%d", width);
  check(dfbwall_options_set(o, "width", size));
  snprintf(size, sizeof size, "%d", height);
  check(dfbwall_options_set(o, "height", size));
  check(dfbwall_options_set(o, "threads", "1"));
  check(dfbwall_options_set(o, "timeout", "120"));
  dfbwall_session* s = NULL;
  check(dfbwall_session_new(MPI_COMM_WORLD, o, &s));
  dfbwall_options_release(o);
  dfbwall_style* st = NULL;
  check(dfbwall_style_new(&st));
  const int dims[3] = {g, g, g};
  const float origin[3] = {0, 0, 0}, spacing[3] = {1, 1, 1}, color[3] = {1.0f, 0.85f, 0.4f};
  check(dfbwall_style_add_volume(st, "volume", dims, origin, spacing, NULL));
  check(dfbwall_style_set_transfer_function(st, 0, "viridis", 0.05f));
  check(dfbwall_style_set_value_range(st, 0, 0, 1));
  check(dfbwall_style_add_isosurface(st, 0, 0.3f, color, 1.0f));
  check(dfbwall_style_set_seed(st, 7));
  check(dfbwall_session_set_style(s, st));
  dfbwall_style_release(st);
  dfbwall_volume_part part = {{0, 0, lo}, {g, g, hi}, DFBWALL_FLOAT32, u};
  dfbwall_brick b = {0};
  b.id = rank;
  b.bounds_lo[2] = (float)z0;
  b.bounds_hi[0] = b.bounds_hi[1] = (float)(g - 1);
  b.bounds_hi[2] = (float)z1;
  b.volumes = &part;
  b.volume_count = 1;
  for (int f = 0; f < frames; ++f) {
    const double a = 0.1 * f, r = 2.2 * g;
    const float position[3] = {(float)(c + r * sin(a)), (float)(c + 0.5 * r),
                               (float)(c - r * cos(a))};
    const float at[3] = {(float)c, (float)c, (float)c}, up[3] = {0, 1, 0};
    check(dfbwall_session_set_camera(s, position, at, up, 40));
    const double t0 = nowMs();
    const clock_t c0 = clock();
    check(dfbwall_session_clear_bricks(s));
    check(dfbwall_session_add_brick_borrowed(s, &b));
    calls[f] = nowMs() - t0;
    check(dfbwall_session_render_frame(s));
    ms[f] = nowMs() - t0;
    cpu[f] = 1e3 * (double)(clock() - c0) / CLOCKS_PER_SEC;
  }
  check(dfbwall_session_write_image(s, argv[4]));
  check(dfbwall_session_close(s));
  dfbwall_session_release(s);
  if (rank == 0) {
    printf("{\"language\": \"c\", \"frame_ms\": [");
    for (int f = 0; f < frames; ++f) printf("%s%f", f ? ", " : "", ms[f]);
    printf("], \"cpu_ms\": [");
    for (int f = 0; f < frames; ++f) printf("%s%f", f ? ", " : "", cpu[f]);
    printf("], \"calls_ms\": [");
    for (int f = 0; f < frames; ++f) printf("%s%f", f ? ", " : "", calls[f]);
    printf("]}\n");
  }
  free(u);
  free(ms);
  free(cpu);
  free(calls);
  MPI_Finalize();
  return 0;
}
