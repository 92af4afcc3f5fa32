#pragma once
// Output files that are never seen half-written (docs/design.md, "Outputs"): the bytes go to a
// temporary with a fresh random name in the target's own folder (so the rename cannot cross file
// systems, and two runs never share a temporary name), are fsync'ed, and the temporary is then
// renamed over the target. A crash or a full disk leaves the old file or none, never a torso.
// Files get the mode the umask leaves of 0666 (docs/security.md, "Captures stay in their
// folder"); a symbolic link at the target's own name is an error, never followed or replaced.
#include <cstdio>
#include <string>

#include "base/FileDescriptor.h"

namespace base {

class AtomicFile {
 public:
  // `path`: its folder is taken as given (links on the way followed: the operator's own path).
  // Creates the temporary, hidden (".NAME.XXXXXX") so globs for outputs never match it.
  // Throws base::Error naming the path.
  explicit AtomicFile(const std::string& path);
  // `name` (one path component) in the open folder `folder` (duplicated: the caller keeps its
  // own); `shownPath` names the file in messages.
  AtomicFile(int folder, const std::string& name, const std::string& shownPath);
  ~AtomicFile();  // removes the temporary unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  FILE* stream() { return file_; }
  // Flushes, fsyncs, closes and renames; throws base::Error naming the path (and removes the
  // temporary) when any step fails, e.g. ENOSPC, or a symbolic link at the target's name.
  void commit();

 private:
  void createTemporary();

  FileDescriptor folder_;
  std::string name_, shown_, temporary_;
  FILE* file_ = nullptr;
  bool committed_ = false;
};

// For setup, before any frame: makes `folder` (with its parents) when missing and checks that a
// file can be created in it. Returns the problem, or an empty string.
std::string checkWritableFolder(const std::string& folder);

}  // namespace base
