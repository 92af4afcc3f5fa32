#pragma once
// A folder that others may name places in, and nothing is ever written outside of: a service
// wall's --capture-root, where each job names its capture folder (docs/security.md, "Captures
// stay in their folder"). The root is opened once; every folder beneath it is then reached from
// that descriptor one component at a time with O_NOFOLLOW (what openat2's RESOLVE_NO_SYMLINKS
// does, without needing it from the kernel or a container's seccomp filter), so neither a
// symbolic link nor a rename made meanwhile leads out of it.
#include <string>

#include "base/FileDescriptor.h"

namespace base {

class ConfinedFolder {
 public:
  // Opens `root`, which must be an existing folder; throws base::Error naming it. `rootName`
  // ("the capture root") is how messages call it.
  ConfinedFolder(const std::string& root, std::string rootName);

  const std::string& path() const { return root_; }
  int fd() const { return fd_.get(); }

  // The folder `request` names, as a path relative to the root ("" is the root itself): a
  // relative request is taken inside the root, an absolute one must lie in it. Refused, with a
  // base::Error that names the root: `..`, an absolute path elsewhere, a symbolic link or a
  // file among the parts that exist, and a deepest existing part this process cannot write in.
  // Creates nothing.
  std::string resolve(const std::string& request) const;
  // Opens the folder `relative` (as resolve returned it) beneath the root, making the parts that
  // are missing (mode 0777 less the umask) when `create`; a symbolic link on the way is refused.
  // Throws base::Error.
  FileDescriptor openFolder(const std::string& relative, bool create) const;

 private:
  std::string root_;       // as given
  std::string canonical_;  // with links resolved, for absolute requests that spell it so
  std::string rootName_;
  FileDescriptor fd_;
};

}  // namespace base
