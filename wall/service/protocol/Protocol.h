#pragma once
// The wall service's wire protocol (docs/service.md, "A wall that stays up"). Render jobs reach a
// persistent wall (`dfbwall serve`) over ZeroMQ (wall/service/protocol/Zmq.h):
//
//  - render rank 0 <-> wall process 0, the wall's directory socket (`--listen`): Hello, then
//    Directory | Refused | Queued; during the job Keepalive, Capture, Bye from the job and
//    Presented (the credit for frames in flight), Roster (a wall process was lost or came back),
//    Refused (a capture request it will not take), Input (a key or the mouse over the job's
//    window on the wall) and Ended (the wall ended the job) back;
//  - every render rank -> the wall processes its tiles touch, each process's piece socket (its
//    endpoint is in the directory): one Batch per (render rank, display, frame) of pieces,
//    encoded with the job's codec (wall/service/protocol/Codec.h).
//
//  - the wall's own processes among themselves (wall/service/protocol/LinkMessages.h): Join,
//    Welcome, Beat, Command, Barrier, Pixels, Dropped, on the same directory socket of process 0
//    (the head).
//
// Every message starts with a MessageHeader (magic, protocol version, kind, session id). The
// wall never trusts a length, count, rectangle, display index or frame number from the wire:
// parse* functions check every field against the message's size and throw base::Error naming
// what was wrong; callers check the rest against the session (wall/display/WallNode.h).
#include <cstdint>
#include <string>
#include <vector>

#include "dfb/Tile.h"
#include "messaging/Compression.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Window.h"
#include "wall/service/protocol/Codec.h"

namespace wall::service {

constexpr std::uint32_t kMagic = 0x57424644;  // "DFBW"
// 2: wall processes come and go (Roster, live flags in the directory, the wall link).
// 3: a job asks for a window of the wall (Hello.window); its directory is the window's layout.
// 4: a running job's window moves or changes size (Reshape; Hello.canReshape).
constexpr std::uint16_t kProtocolVersion = 4;
// Caps of what one message part may say, per socket, checked by libzmq before anything is
// allocated (ZMQ_MAXMSGSIZE; a peer that announces more is disconnected):
//  - the directory socket of the head (and a relay's socket for jobs) carries hellos, controls
//    and the wall's own link; a wall process's captured pixels reach the head in parts of this
//    size (joined there, up to kMaxMessageBytes, from processes that are members only);
constexpr std::size_t kMaxLinkMessageBytes = std::size_t{64} << 10;
//  - a piece socket carries batches, which a job flushes at 4 MiB: the last piece added (a tile
//    of at most 1024 x 1024 pixels, encoded) may take one past that;
constexpr std::size_t kMaxBatchBytes = std::size_t{16} << 20;
//  - what a job or member receives from the wall (a directory, a roster), and a message joined
//    from parts.
constexpr std::size_t kMaxMessageBytes = std::size_t{1} << 30;
constexpr std::size_t kMaxStringBytes = 4096;

enum class Kind : std::uint16_t {
  Hello = 1,
  Directory = 2,
  Refused = 3,
  Queued = 4,
  Keepalive = 5,
  Capture = 6,
  Bye = 7,
  Presented = 8,
  Ended = 9,
  Batch = 10,
  Roster = 11,
  // The wall's own link (wall/service/protocol/LinkMessages.h); a job never sends or gets these.
  Join = 12,
  Welcome = 13,
  Beat = 14,
  Command = 15,
  Barrier = 16,
  Pixels = 17,
  Dropped = 18,
  Reshape = 19,    // wall -> job: its window moves or changes size from a frame on
  Input = 20,      // wall -> job: an operator's key or mouse event over its window (WindowInput)
  Thumbnail = 21,  // member -> head: its cells of a window's thumbnail (LinkMessages.h)
};
constexpr Kind kLastKind = Kind::Thumbnail;

struct MessageHeader {
  std::uint32_t magic = kMagic;
  std::uint16_t version = kProtocolVersion;
  std::uint16_t kind = 0;
  std::uint64_t session = 0;  // 0 before the directory gave one
};
static_assert(sizeof(MessageHeader) == 16, "the header is part of the protocol");

// The first thing a job says.
struct Hello {
  // Unused: the token is checked at the ZeroMQ handshake (wall/service/security/); sent empty.
  std::string token;
  std::string host;  // the job's rank-0 host, for the wall's log and the busy message
  std::uint32_t renderRanks = 1;
  std::uint32_t tileSize = 64;
  CodecSpec codec;
  std::uint32_t framesInFlight = 2;
  bool wait = false;       // queue behind the connected job instead of being refused
  std::string captureDir;  // on the wall hosts; empty: no captures
  std::uint32_t captureEvery = 0;
  // The part of the wall the job covers (wall/layout/Window.h); the wall resolves it against its
  // layout and refuses one that is empty, outside its canvas or names no display of it.
  WindowRequest window;
  // The job can re-plan its frame buffer for a new window while it runs (Reshape); a job that
  // cannot is refused a move or resize with a reason, and keeps its window.
  bool canReshape = false;
  // For the wall's window manager (serve --control): what the job renders ("scivis
  // builtin:wavelet"), and the address of its own control page (`--control`), empty when none.
  std::string job;
  std::string page;
};

// The fields of a job that its hello carries and each wall process's Start repeats: the head
// checks them in the hello, and every process again in its Start (it never trusts that the head
// did). Empty when they are fine, else the first field that is wrong, with its range.
struct JobFields {
  std::uint32_t renderRanks = 1, tileSize = 64, codec = 0, framesInFlight = 2, captureEvery = 0;
};
std::string jobFieldsProblem(const JobFields& fields);

struct DirectoryProcess {
  std::string endpoint;  // "tcp://HOST:PORT" of the process's piece socket
  bool live = true;      // false: the process is lost; pieces of its displays are not sent
};

// What the wall tells a job it accepted: everything needed to route pieces to the displays.
struct Directory {
  std::uint64_t session = 0;
  // The job's window's layout (wall/layout/Window.h: windowLayout): canvas = the window, the
  // displays it touches clipped to it, in window coordinates, with the wall's names and process
  // indices (which may leave gaps); processCount = the wall's. For the whole wall, the wall's.
  Layout layout;
  dfb::Region window;  // the window on the wall's canvas (its size is the layout's canvas)
  std::vector<DirectoryProcess> processes;
  std::uint32_t framesInFlight = 2;  // what the wall grants (at most what the job asked for)
  std::uint32_t timeoutMs = 60000;   // the wall drops a job it has not heard from for this long
  std::uint32_t rosterVersion = 0;   // of `processes`; a Roster with a higher one replaces them
};

// The wall's processes changed during a job: one was lost (dropped from the swap barrier; the
// job stops sending its displays' pieces, counting them as dropped) or (re)joined (the job sends
// its pieces again, at the latest from `fromFrame`, to the endpoint named here, which changes
// when a process restarts). Sent before the credit that lets the job start `fromFrame`, so a job
// that applies the newest roster it has at the start of each frame is never late.
struct Roster {
  std::uint64_t session = 0;
  std::uint32_t version = 0;
  std::uint32_t fromFrame = 0;  // 0: a loss (at once)
  std::vector<DirectoryProcess> processes;
  std::string why;  // one line for the job's log: which process, which host, why
};

// A running job's window moves or changes size (docs/design.md, "Moving and resizing a window"):
// from frame `fromFrame` on, the job renders the new window (its canvas, displays and processes
// in `directory`, as a directory says them) and stamps its pieces with `directory.session`, a
// piece session of its own, so no piece of one shape lands in the other's node. Sent before the
// credit that lets the job start `fromFrame`; the job applies the newest one it has once its
// frame order reaches that frame. `version` counts a job's reshapes from 1.
struct Reshape {
  std::uint64_t session = 0;  // the job's
  std::uint32_t version = 0;
  std::uint32_t fromFrame = 0;
  Directory directory;
};

// An operator's key or mouse event in a wall window (wall/display/Presenter.h, WallInput), over a
// job's window: the wall process sends it to the head on the canvas (Command::Input), the head
// checks it and tells the job in its window's pixels (Kind::Input), which steers as its control
// API does (docs/service.md, "Several jobs at once": input).
struct WindowInput {
  enum Kind : std::uint32_t { kKey = 1, kDrag = 2, kScroll = 3 };
  // The keys a job is told of (wall::WallKey's first six, in its order); Esc stays on the wall.
  enum Key : std::uint32_t { kLeft = 0, kRight, kUp, kDown, kPlus, kMinus, kKeyCount };
  std::uint32_t kind = kKey;
  std::uint32_t key = kLeft;    // kKey
  std::int32_t x = 0, y = 0;    // where the cursor was (kDrag: where the button went down)
  std::int32_t dx = 0, dy = 0;  // kDrag: pixels moved; kScroll: dy notches, up positive
  bool pan = false;             // kDrag: pan rather than orbit
};
// The most a drag or wheel event may move (pixels, notches) in one message.
constexpr std::int32_t kMaxInputMove = 1 << 16;
messaging::Bytes packInput(std::uint64_t session, const WindowInput& input);
// Checks the kind, the key, the move's size and the flag; the position is the caller's to check.
WindowInput parseInput(const std::byte* data, std::size_t size);

messaging::Bytes packHello(const Hello& hello);
messaging::Bytes packReshape(const Reshape& reshape);
// The directory's checks, a version and frame above 0, a piece session neither 0 nor the job's.
Reshape parseReshape(const std::byte* data, std::size_t size);
messaging::Bytes packDirectory(const Directory& directory);
messaging::Bytes packRoster(const Roster& roster);
// Refused, Ended: a reason (a Refused with a job's session refuses one request of the job, a
// capture, and the job goes on). Queued: the job's place in the queue as text.
messaging::Bytes packText(Kind kind, std::uint64_t session, const std::string& text);
// Keepalive (value unused), Bye (the last frame), Capture (frame, sequence in `second`),
// Presented (frame, completeNs in `second`).
messaging::Bytes packControl(Kind kind, std::uint64_t session, std::uint64_t value,
                             std::int64_t second = 0);

// The header of any message, checked (magic, version, a known kind); throws base::Error with a
// message a log can print ("not the dfbwall protocol", "protocol version 7, this wall speaks 1").
MessageHeader parseHeader(const std::byte* data, std::size_t size);
Hello parseHello(const std::byte* data, std::size_t size);
// Also validates the layout (a wall that sends nonsense is an error on the job's side too).
Directory parseDirectory(const std::byte* data, std::size_t size);
// Process count 1..kMaxDisplays, endpoints non-empty for live processes. The job checks the
// count against its directory.
Roster parseRoster(const std::byte* data, std::size_t size);
std::string parseText(const std::byte* data, std::size_t size);
struct Control {
  std::uint64_t value = 0;
  std::int64_t second = 0;
};
Control parseControl(const std::byte* data, std::size_t size);

// A batch of pieces of one display and frame from one render rank.
struct BatchHeader {
  std::uint32_t frameId = 0;
  std::int32_t display = -1;
  std::uint32_t renderRank = 0;
  Codec codec = Codec::Raw;
  std::uint32_t pieceCount = 0;
};
struct BatchPiece {
  dfb::Region local;  // in the display's coordinates
  const std::byte* data = nullptr;
  std::size_t size = 0;
};

// What each piece adds to a batch before its pixels: rectangle and encoded size.
constexpr std::size_t kPieceRecordBytes = 20;

// Builds a batch: start it, add pieces (each encoded right into the message), take it.
class BatchWriter {
 public:
  void start(std::uint64_t session, const BatchHeader& header);
  // `pixels`: the piece's top-left pixel in an image of rows `stride` pixels apart.
  void add(const CodecSpec& codec, const dfb::Region& local, const std::uint32_t* pixels,
           int stride);
  // A piece encoded beforehand by encodePiece (so encoding needs no lock around the batch).
  void append(const messaging::Bytes& piece);
  std::uint32_t pieces() const { return pieces_; }
  std::size_t bytes() const { return bytes_.size(); }
  messaging::Bytes take();

 private:
  messaging::Bytes bytes_;
  std::uint32_t pieces_ = 0;
};

// One piece's record and encoded pixels, as BatchWriter::add would write them, into `out`
// (replacing what it held).
void encodePiece(const CodecSpec& codec, const dfb::Region& local, const std::uint32_t* pixels,
                 int stride, messaging::Bytes& out);

// Parses a whole batch; every piece's rectangle is non-empty and at most 4096 pixels a side,
// every data range inside the message. Throws base::Error.
BatchHeader parseBatch(const std::byte* data, std::size_t size, std::vector<BatchPiece>& pieces);

}  // namespace wall::service
