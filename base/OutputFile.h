#pragma once
// Files written in place, such as statistics streams: opened without following a symbolic link
// at their own name (one planted there would send the output elsewhere), with the mode the umask
// leaves of 0666 (docs/security.md, "Captures stay in their folder").
#include <cstdio>
#include <string>

#include "base/FileDescriptor.h"

namespace base {

// Appends to `path` or truncates it (`append` false), creating it when missing. Throws
// base::Error naming the path and the reason.
FileDescriptor openOutputFile(const std::string& path, bool append);
// The same as a stdio stream, which the caller closes.
std::FILE* openOutputStream(const std::string& path, bool append);

}  // namespace base
