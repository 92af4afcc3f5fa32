#pragma once
// Output files that are never seen half-written (docs/design.md, "Outputs"): the bytes go to a
// temporary made by mkstemp in the target's own folder (so the rename cannot cross file
// systems, and two runs never share a temporary name), are fsync'ed, and the temporary is then
// renamed over the target. A crash or a full disk leaves the old file or none, never a torso.
#include <cstdio>
#include <string>

namespace base {

class AtomicFile {
 public:
  // Creates the temporary, hidden (".NAME.XXXXXX") so globs for outputs never match it, with
  // mode 0644. Throws base::Error naming the path.
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();  // removes the temporary unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  FILE* stream() { return file_; }
  // Flushes, fsyncs, closes and renames; throws base::Error naming the path (and removes the
  // temporary) when any step fails, e.g. ENOSPC.
  void commit();

 private:
  std::string path_, temporary_;
  FILE* file_ = nullptr;
  bool committed_ = false;
};

// For setup, before any frame: makes `folder` (with its parents) when missing and checks that a
// file can be created in it. Returns the problem, or an empty string.
std::string checkWritableFolder(const std::string& folder);

}  // namespace base
