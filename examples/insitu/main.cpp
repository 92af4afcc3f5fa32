// In-situ visualization with dfbwall's data-distributed API: an MPI program that evolves the heat
// equation on a 3-D grid cut into slabs (each rank its slabs, with the stencil's ghost planes
// exchanged by MPI every step) and shows every K-th step on a display wall, straight from the
// simulation's memory: no file is written (but the wall's captures, when asked for). The
// renderer's own ghosts are the session's business (Ghosts::Exchange): a slab gives the planes it
// owns.
//
//   mpirun -np 6 insitu --wall 2x2.toml --capture caps    # 2 simulating ranks, 4 wall ranks
//   mpirun -np 2 insitu --size 400x300 --image last.png   # no wall: the last frame as a PNG
//   mpirun -np 2 insitu --connect wall0:7000 --token-file F   # a wall that `dfbwall serve` runs
//                      (the wall's token: F, else DFBWALL_TOKEN, else serve's default file)
//
// The grid is cut into --blocks slabs whatever the rank count (rank r holds slabs r, r + R, ...),
// so any number of ranks computes the same field and shows the same pixels.
#include <dfbwall/DataDistributed.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace {

struct Args {
  int grid = 48, blocks = 4, steps = 40, showEvery = 10;
  dfbwall::SessionOptions session;
  std::string image;  // without a wall: the last frame as a PNG
};

[[noreturn]] void usage(const char* problem) {
  std::fprintf(
      stderr,
      "insitu: %s\nusage: insitu [--grid N] [--blocks B] [--steps S] [--show-every K]\n"
      "              [--wall LAYOUT.toml [--windows] [--capture DIR]]\n"
      "              [--connect HOST:PORT [--token-file F] [--server-key F] [--codec C] [--wait]\n"
      "               [--window X,Y,W,H|DISPLAY|full] [--capture DIR]]\n"
      "              [--size WxH --image FILE.png] [--threads T]\n",
      problem);
  std::exit(2);
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(("missing value of " + k).c_str());
      return argv[++i];
    };
    if (k == "--grid")
      a.grid = std::atoi(value().c_str());
    else if (k == "--blocks")
      a.blocks = std::atoi(value().c_str());
    else if (k == "--steps")
      a.steps = std::atoi(value().c_str());
    else if (k == "--show-every")
      a.showEvery = std::atoi(value().c_str());
    else if (k == "--wall")
      a.session.wall = value();
    else if (k == "--connect")
      a.session.connect = value();
    else if (k == "--token-file")
      a.session.tokenFile = value();
    else if (k == "--server-key")
      a.session.serverKeyFile = value();
    else if (k == "--codec")
      a.session.codec = value();
    else if (k == "--wait")
      a.session.wait = true;
    else if (k == "--window")
      a.session.window = value();
    else if (k == "--windows")
      a.session.offscreen = false;
    else if (k == "--capture")
      a.session.captureDir = value();
    else if (k == "--threads")
      a.session.threads = std::atoi(value().c_str());
    else if (k == "--image")
      a.image = value();
    else if (k == "--size") {
      if (std::sscanf(value().c_str(), "%dx%d", &a.session.width, &a.session.height) != 2)
        usage("--size wants WxH");
    } else
      usage(("unknown option " + k).c_str());
  }
  if (a.grid < 8 || a.blocks < 1 || a.steps < 1 || a.showEvery < 1) usage("bad numbers");
  return a;
}

// The simulation's own data: one slab of the N^3 grid, planes [z0, z1) owned, kGhost planes on
// either side copied from the neighbouring slabs for the stencil.
constexpr int kGhost = 1;

struct Slab {
  int id = 0, z0 = 0, z1 = 0;
  std::vector<float> u, next;  // (z1 - z0 + 2 kGhost) planes of N x N, x fastest
};

float& at(std::vector<float>& f, const Slab& s, int n, int x, int y, int z) {
  return f[(static_cast<std::size_t>(z - s.z0 + kGhost) * n + y) * n + x];
}

// Hot spots at the start, and a small source that stays hot: something to watch spread.
float initial(int n, int x, int y, int z) {
  const float h = 2.0f / static_cast<float>(n - 1);
  const float px = -1 + h * x, py = -1 + h * y, pz = -1 + h * z;
  const float a = (px - 0.35f) * (px - 0.35f) + py * py + (pz + 0.3f) * (pz + 0.3f);
  const float b =
      (px + 0.4f) * (px + 0.4f) + (py - 0.3f) * (py - 0.3f) + (pz - 0.35f) * (pz - 0.35f);
  return std::exp(-a / 0.04f) + 0.8f * std::exp(-b / 0.08f);
}
bool isSource(int n, int x, int y, int z) {
  const int c = n / 2, r = std::max(1, n / 16);
  return std::abs(x - c) <= r && std::abs(y - n / 4) <= r && std::abs(z - c) <= r;
}

// Ghost planes from the neighbouring slabs (on this rank or another): every slab sends its
// lowest and highest kGhost owned planes; the messages' tags name the receiving slab and side.
void exchangeGhosts(std::vector<Slab>& mine, int n, int blocks, MPI_Comm comm) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  const std::size_t plane = static_cast<std::size_t>(n) * n, count = kGhost * plane;
  std::vector<MPI_Request> requests;
  for (Slab& s : mine) {
    const std::size_t owned = static_cast<std::size_t>(s.z1 - s.z0);
    if (s.id > 0) {  // below: the slab id - 1
      const int peer = (s.id - 1) % ranks;
      requests.emplace_back();
      MPI_Irecv(s.u.data(), static_cast<int>(count), MPI_FLOAT, peer, 2 * s.id, comm,
                &requests.back());
      requests.emplace_back();
      MPI_Isend(s.u.data() + count, static_cast<int>(count), MPI_FLOAT, peer, 2 * (s.id - 1) + 1,
                comm, &requests.back());
    }
    if (s.id + 1 < blocks) {  // above: the slab id + 1
      const int peer = (s.id + 1) % ranks;
      requests.emplace_back();
      MPI_Irecv(s.u.data() + count + owned * plane, static_cast<int>(count), MPI_FLOAT, peer,
                2 * s.id + 1, comm, &requests.back());
      requests.emplace_back();
      MPI_Isend(s.u.data() + owned * plane, static_cast<int>(count), MPI_FLOAT, peer,
                2 * (s.id + 1), comm, &requests.back());
    }
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
}

// One explicit step of u_t = laplace(u) (r = dt / h^2 = 0.15 < 1/6: stable); the faces of the
// grid stay cold, the source stays hot. Each voxel is computed the same way whichever slab or
// rank holds it, so the field never depends on the decomposition.
void step(Slab& s, int n) {
  constexpr float r = 0.15f;
  s.next = s.u;
  for (int z = s.z0; z < s.z1; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        float& out = at(s.next, s, n, x, y, z);
        if (x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1) {
          out = 0;
          continue;
        }
        if (isSource(n, x, y, z)) {
          out = 1;
          continue;
        }
        const float c = at(s.u, s, n, x, y, z);
        const float sum = at(s.u, s, n, x - 1, y, z) + at(s.u, s, n, x + 1, y, z) +
                          at(s.u, s, n, x, y - 1, z) + at(s.u, s, n, x, y + 1, z) +
                          at(s.u, s, n, x, y, z - 1) + at(s.u, s, n, x, y, z + 1);
        out = c + r * (sum - 6 * c);
      }
  std::swap(s.u, s.next);
}

// The slab as a brick: clipped to its own planes (up to the next slab's first), its voxels the
// planes it owns; the session exchanges the ghosts its renderer reads.
dfbwall::Brick brickOf(const Slab& s, int n) {
  const float h = 2.0f / static_cast<float>(n - 1);
  dfbwall::Brick b;
  b.id = s.id;
  b.boundsLo = {-1, -1, -1 + h * s.z0};
  b.boundsHi = {1, 1, -1 + h * std::min(s.z1, n - 1)};
  dfbwall::VolumePart part;
  part.lo = {0, 0, s.z0};
  part.hi = {n, n, s.z1};
  part.type = dfbwall::VoxelType::Float32;
  part.voxels = s.u.data() + static_cast<std::size_t>(kGhost) * n * n;
  part.ghosts = dfbwall::Ghosts::Exchange;
  b.volumes.push_back(part);
  return b;
}

dfbwall::Style style(int n) {
  dfbwall::Style st;
  dfbwall::VolumeStyle v;
  v.name = "temperature";
  v.grid.dims = {n, n, n};
  v.grid.origin = {-1, -1, -1};
  const float h = 2.0f / static_cast<float>(n - 1);
  v.grid.spacing = {h, h, h};
  v.transferFunction = "inferno";
  v.autoRange = false;  // a fixed scale, so colours mean the same temperature in every frame
  v.valueMin = 0;
  v.valueMax = 1;
  v.maxOpacity = 0.5f;
  st.volumes.push_back(v);
  st.isosurfaces.push_back({0, 0.1f, {0.3f, 0.6f, 1.0f}, 0.3f});
  st.isosurfaces.push_back({0, 0.4f, {1.0f, 0.85f, 0.4f}, 1.0f});
  st.background = {0.005f, 0.005f, 0.01f};
  st.seed = 7;
  return st;
}

int run(const Args& args) {
  dfbwall::Session session(MPI_COMM_WORLD, args.session);
  if (session.isWallRank()) {
    session.runWall();  // until the simulation's ranks close the session
    return 0;
  }
  MPI_Comm sim = session.renderComm();
  int rank = 0, ranks = 1;
  MPI_Comm_rank(sim, &rank);
  MPI_Comm_size(sim, &ranks);
  const int n = args.grid;
  if (n / args.blocks < kGhost) {
    if (rank == 0) std::fprintf(stderr, "insitu: slabs under %d planes thick\n", kGhost);
    return 2;
  }
  std::vector<Slab> mine;
  for (int b = rank; b < args.blocks; b += ranks) {
    Slab s;
    s.id = b;
    s.z0 = n * b / args.blocks;
    s.z1 = n * (b + 1) / args.blocks;
    s.u.assign(static_cast<std::size_t>(s.z1 - s.z0 + 2 * kGhost) * n * n, 0.0f);
    for (int z = s.z0; z < s.z1; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) at(s.u, s, n, x, y, z) = initial(n, x, y, z);
    mine.push_back(std::move(s));
  }
  session.setStyle(style(n));
  dfbwall::Camera camera;
  camera.position = {1.7f, 1.2f, -2.0f};
  camera.lookAt = {0, 0, 0};
  camera.fovY = 40;
  session.setCamera(camera);

  exchangeGhosts(mine, n, args.blocks, sim);
  for (int t = 1; t <= args.steps; ++t) {
    for (Slab& s : mine) step(s, n);
    exchangeGhosts(mine, n, args.blocks, sim);
    if (t % args.showEvery != 0) continue;
    // A new scene version: this step's field, straight from the simulation's arrays.
    session.clearBricks();
    for (const Slab& s : mine) session.addBrick(brickOf(s, n));
    session.renderFrame();
    if (rank == 0) std::printf("step %d shown (frame %u)\n", t, session.framesRendered());
  }
  // What the session exchanged for the last frame shown, over every rank (between bricks on one
  // rank it copies, and that is not counted).
  unsigned long long ghosts = session.ghostBytesReceived(), allGhosts = 0;
  MPI_Reduce(&ghosts, &allGhosts, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, sim);
  if (rank == 0)
    std::printf("brick data on rank 0: %zu bytes; ghost voxels sent between ranks: %llu bytes\n",
                session.sceneBytes(), allGhosts);
  if (!args.image.empty()) session.writeImage(args.image);
  session.close();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided);
  const Args args = parse(argc, argv);
  int code = 0;
  try {
    code = run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "insitu: %s\n", e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return code;
}
