#pragma once
// What the wall's processes tell each other about a render job (wall/service/server/WallService.h):
// the head's orders to every process and each process's answers to the head. They travel over the
// wall link (wall/service/protocol/LinkMessages.h, Kind::Command) or, for the head's own process,
// inside the process.
#include <cstdint>
#include <string>

#include "messaging/Compression.h"

namespace wall::service {

enum class Command : std::uint32_t {
  Start = 1,      // a job: run a wall node for it (text: its capture folder; a: its first frame, or
                  // 0 for a process joining a running job: FirstFrame follows its Ready; b: its
                  // window's stacking order, higher on top)
  Cancel = 2,     // the job never started (a process could not): stop before frame 1
  LastFrame = 3,  // a: the job's last frame
  Abort = 4,      // the job is gone (text: why): give the frame in progress up
  KeepWaiting = 5,  // the job is alive but idle
  Capture = 6,      // a: frame, b: sequence
  Shutdown = 7,     // the wall stops
  Ready = 8,        // a: 1 ready, 0 not (text: why)
  Done = 9,         // a: last presented frame, b: bytes received (text: failure, if any)
  Failed = 10,      // this process gave a frame up (text: why)
  StopAsked = 11,   // this process was asked to stop the wall
  FirstFrame = 12,  // a: the first frame of a process that joined a running job
  // The job's window moves (docs/design.md, "Moving and resizing a window"): build its node for
  // the window in the header beside the running one, taking the pieces stamped with the header's
  // piece session; answer Reshaped. Its first frame follows in ReshapeAt.
  Reshape = 13,
  ReshapeAt = 14,  // a: the frame the node of the piece session takes over (0: drop it)
  Reshaped = 15,   // a: 1 built, 0 not (text: why); the piece session built
  // A key or the mouse in this process's windows over the job's window (text: packInput's
  // message, the position on the wall's canvas); the head checks it and tells the job.
  Input = 16,
  Raise = 17,  // a: the job's window's new stacking order (above every other window's)
  // The head asks for the windows' thumbnails (serve --control): a: the request's number, b: the
  // thumbnail's longest side. Each process answers with its cells of every window it shows
  // (ProcessLink::thumbnail).
  Thumbnails = 18,
};

struct CommandHeader {
  Command kind;
  std::int32_t process;
  std::uint64_t session;
  std::int64_t a, b;
  // Start, Reshape, ReshapeAt, Reshaped: what the job's pieces for the window are stamped with
  // (a moved window's own; 0 in a Start: the job's session).
  std::uint64_t pieceSession;
  std::uint32_t tileSize, renderRanks, framesInFlight, captureEvery;
  std::uint32_t codec;
  // Start: the job's window on the wall's canvas (resolved by the head; each process checks it).
  std::int32_t windowX0, windowY0, windowX1, windowY1;
  std::uint32_t textBytes;
};

static_assert(sizeof(CommandHeader) == 80, "the wall link's command layout (no padding)");

struct ServiceCommand {
  CommandHeader header{};
  std::string text;
};

messaging::Bytes packCommand(const ServiceCommand& command);
// Throws base::Error on a body that is not a command.
ServiceCommand parseCommand(const messaging::Bytes& body);
// What is wrong with a Start (a session, its first frame, the job's fields as a hello's: see
// jobFieldsProblem); empty when nothing is. A wall process checks its Start before it builds
// anything from it.
std::string startProblem(const ServiceCommand& start);

}  // namespace wall::service
