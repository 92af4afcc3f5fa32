// Raw MPI point-to-point bandwidth with tile-sized messages, in the shape of a wall's traffic:
// the first SENDERS ranks stream messages of MESSAGE_BYTES to the other ranks, round robin,
// with a window of outstanding non-blocking sends, for about SECONDS. This is the ceiling the
// DFB's delivery is compared with (figure 2 of scripts/bench). Prints one JSON object.
//   mpiexec -n N p2p_bench SENDERS MESSAGE_BYTES SECONDS
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (argc != 4 || std::atoi(argv[1]) < 1 || std::atoi(argv[1]) >= size) {
    if (rank == 0)
      std::fprintf(stderr, "usage: mpiexec -n N %s SENDERS MESSAGE_BYTES SECONDS\n", argv[0]);
    MPI_Finalize();
    return 2;
  }
  const int senders = std::atoi(argv[1]), receivers = size - senders;
  const int bytes = std::atoi(argv[2]);
  const double seconds = std::atof(argv[3]);
  constexpr int kWindow = 32;  // outstanding messages per rank, as a messenger's queue holds
  std::vector<std::vector<char>> buffers(kWindow, std::vector<char>(static_cast<size_t>(bytes), 1));
  std::vector<MPI_Request> requests(kWindow, MPI_REQUEST_NULL);

  MPI_Barrier(MPI_COMM_WORLD);
  const double start = MPI_Wtime();
  long messages = 0;
  if (rank < senders) {
    int next = 0;
    while (MPI_Wtime() - start < seconds) {
      for (int w = 0; w < kWindow; ++w) {
        const int to = senders + (next++ % receivers);
        MPI_Isend(buffers[w].data(), bytes, MPI_CHAR, to, 1, MPI_COMM_WORLD, &requests[w]);
      }
      MPI_Waitall(kWindow, requests.data(), MPI_STATUSES_IGNORE);
      messages += kWindow;
    }
    // Tell every receiver we are done: a zero-byte message with another tag.
    for (int r = senders; r < size; ++r) MPI_Send(nullptr, 0, MPI_CHAR, r, 2, MPI_COMM_WORLD);
  } else {
    int finished = 0;
    std::vector<char> sink(static_cast<size_t>(bytes));
    while (finished < senders) {
      MPI_Status status;
      MPI_Recv(sink.data(), bytes, MPI_CHAR, MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &status);
      if (status.MPI_TAG == 2)
        ++finished;
      else
        ++messages;
    }
  }
  const double elapsed = MPI_Wtime() - start;
  long total = 0;
  double slowest = 0;
  MPI_Reduce(&messages, &total, 1, MPI_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
  MPI_Reduce(&elapsed, &slowest, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  if (rank == 0) {
    // Messages are counted at the receivers (senders' counts equal them); halve the sum.
    const double received = static_cast<double>(total) / 2.0;
    std::printf(
        "{\"ranks\": %d, \"senders\": %d, \"message_bytes\": %d, \"seconds\": %.3f, "
        "\"messages\": %.0f, \"bytes_per_s\": %.0f, \"mpixels_rgba8_per_s\": %.2f}\n",
        size, senders, bytes, slowest, received, received * bytes / slowest,
        received * bytes / slowest / 4e6);
  }
  MPI_Finalize();
  return 0;
}
