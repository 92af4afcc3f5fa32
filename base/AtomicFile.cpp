#include "base/AtomicFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <random>
#include <system_error>

#include "base/Error.h"

namespace base {
namespace {

// ".NAME." and six random letters or digits, as mkstemp would (mkstemp cannot take a folder fd
// nor a mode).
std::string temporaryName(const std::string& name) {
  static const char kLetters[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 random{std::random_device{}()};
  std::uniform_int_distribution<std::size_t> pick(0, sizeof kLetters - 2);
  // Appended, not "." + string: GCC 12 at -O3 warns falsely (-Wrestrict) about the latter.
  std::string temporary = ".";
  temporary += name;
  temporary += '.';
  for (int i = 0; i < 6; ++i) temporary += kLetters[pick(random)];
  return temporary;
}

}  // namespace

AtomicFile::AtomicFile(const std::string& path) : shown_(path) {
  const std::filesystem::path target(path);
  name_ = target.filename().string();
  const std::string folder = target.parent_path().string();
  folder_ = FileDescriptor(
      open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (!folder_.valid())
    throw Error(shown_ + ": cannot create a temporary file: " + std::strerror(errno));
  createTemporary();
}

AtomicFile::AtomicFile(int folder, const std::string& name, const std::string& shownPath)
    : folder_(fcntl(folder, F_DUPFD_CLOEXEC, 0)), name_(name), shown_(shownPath) {
  if (!folder_.valid())
    throw Error(shown_ + ": cannot create a temporary file: " + std::strerror(errno));
  createTemporary();
}

void AtomicFile::createTemporary() {
  int fd = -1;
  for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
    temporary_ = temporaryName(name_);
    // 0666: the umask decides who else may read the output. O_EXCL never follows a link.
    fd = openat(folder_.get(), temporary_.c_str(),
                O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) throw Error(shown_ + ": cannot create a temporary file: " + std::strerror(errno));
  file_ = fdopen(fd, "wb");
  if (!file_) {
    const int error = errno;
    close(fd);
    unlinkat(folder_.get(), temporary_.c_str(), 0);
    throw Error(shown_ + ": cannot open a temporary file: " + std::strerror(error));
  }
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  if (file_) std::fclose(file_);
  unlinkat(folder_.get(), temporary_.c_str(), 0);
}

void AtomicFile::commit() {
  int error = 0;
  if (std::fflush(file_) != 0 || std::ferror(file_)) error = errno ? errno : EIO;
  if (!error && fsync(fileno(file_)) != 0) error = errno;
  if (std::fclose(file_) != 0 && !error) error = errno;
  file_ = nullptr;
  // A link planted at the target's name is refused rather than replaced: someone put it there to
  // send this output elsewhere, and the operator should hear of it.
  struct stat existing {};
  const bool link = !error &&
                    fstatat(folder_.get(), name_.c_str(), &existing, AT_SYMLINK_NOFOLLOW) == 0 &&
                    S_ISLNK(existing.st_mode);
  if (!error && !link &&
      renameat(folder_.get(), temporary_.c_str(), folder_.get(), name_.c_str()) != 0)
    error = errno;
  if (error || link) {
    unlinkat(folder_.get(), temporary_.c_str(), 0);
    throw Error(shown_ + (link ? ": is a symbolic link; outputs never follow or replace one"
                               : std::string(": cannot write: ") + std::strerror(error)));
  }
  committed_ = true;
  fsync(folder_.get());  // the rename itself is durable once the folder is
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
