#include "base/OutputFile.h"

#include <fcntl.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "base/Error.h"

namespace base {

FileDescriptor openOutputFile(const std::string& path, bool append) {
  const int mode = append ? O_APPEND : O_TRUNC | O_APPEND;
  FileDescriptor fd(open(path.c_str(), O_WRONLY | O_CREAT | O_NOFOLLOW | O_CLOEXEC | mode, 0666));
  if (!fd.valid()) {
    const int error = errno;
    struct stat st {};
    if (error == ELOOP && lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode))
      throw Error(path + ": is a symbolic link; outputs never follow one");
    throw Error(path + ": cannot open it for writing: " + std::strerror(error));
  }
  return fd;
}

std::FILE* openOutputStream(const std::string& path, bool append) {
  FileDescriptor fd = openOutputFile(path, append);
  std::FILE* stream = fdopen(fd.get(), append ? "a" : "w");
  if (!stream) throw Error(path + ": cannot open it for writing: " + std::strerror(errno));
  (void)fd.release();
  return stream;
}

}  // namespace base
