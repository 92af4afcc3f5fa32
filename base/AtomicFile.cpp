#include "base/AtomicFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "base/Error.h"

namespace base {
namespace {

std::string temporaryPattern(const std::string& path) {
  const std::filesystem::path target(path);
  // Appended, not "." + string: GCC 12 at -O3 warns falsely (-Wrestrict) about the latter.
  std::string name = ".";
  name += target.filename().string();
  name += ".XXXXXX";
  return (target.parent_path() / name).string();
}

}  // namespace

AtomicFile::AtomicFile(const std::string& path) : path_(path), temporary_(temporaryPattern(path)) {
  const int fd = mkstemp(temporary_.data());
  if (fd < 0) throw Error(path_ + ": cannot create a temporary file: " + std::strerror(errno));
  fchmod(fd, 0644);  // mkstemp makes it 0600; outputs are for other users too
  file_ = fdopen(fd, "wb");
  if (!file_) {
    const int error = errno;
    close(fd);
    unlink(temporary_.c_str());
    throw Error(path_ + ": cannot open a temporary file: " + std::strerror(error));
  }
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (file_) std::fclose(file_);
  unlink(temporary_.c_str());
}

void AtomicFile::commit() {
  int error = 0;
  if (std::fflush(file_) != 0 || std::ferror(file_)) error = errno ? errno : EIO;
  if (!error && fsync(fileno(file_)) != 0) error = errno;
  if (std::fclose(file_) != 0 && !error) error = errno;
  file_ = nullptr;
  if (!error && std::rename(temporary_.c_str(), path_.c_str()) != 0) error = errno;
  if (error) {
    unlink(temporary_.c_str());
    throw Error(path_ + ": cannot write: " + std::strerror(error));
  }
  committed_ = true;
  // The rename itself is durable once the folder is.
  const std::string folder = std::filesystem::path(path_).parent_path().string();
  const int dir = open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (dir >= 0) {
    fsync(dir);
    close(dir);
  }
}

std::string checkWritableFolder(const std::string& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) return folder + ": cannot create the folder: " + ec.message();
  std::string probe = (std::filesystem::path(folder) / ".dfbwall-probe.XXXXXX").string();
  const int fd = mkstemp(probe.data());
  if (fd < 0) return folder + ": cannot create files there: " + std::strerror(errno);
  close(fd);
  unlink(probe.c_str());
  return {};
}

}  // namespace base
