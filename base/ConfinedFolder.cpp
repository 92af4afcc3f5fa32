#include "base/ConfinedFolder.h"

#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "base/Error.h"

namespace base {
namespace {

constexpr std::size_t kMaxDepth = 64;  // folders beneath the root; deeper is not a capture folder

// The components of `path`, without empty and "." ones.
std::vector<std::string> partsOf(const std::string& path) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (begin <= path.size()) {
    std::size_t end = path.find('/', begin);
    if (end == std::string::npos) end = path.size();
    std::string part = path.substr(begin, end - begin);
    if (!part.empty() && part != ".") parts.push_back(std::move(part));
    begin = end + 1;
  }
  return parts;
}

std::string joined(const std::vector<std::string>& parts, std::size_t count) {
  std::string out;
  for (std::size_t i = 0; i < count; ++i) out += (i ? "/" : "") + parts[i];
  return out;
}

bool isControl(char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }

// A request as messages show it: it may come from the network, so control characters become '?'
// and a long one is cut.
std::string shown(const std::string& request) {
  constexpr std::size_t kShown = 200;
  std::string out;
  for (const char c : request.substr(0, kShown)) out += isControl(c) ? '?' : c;
  return request.size() > kShown ? out + "..." : out;
}

bool startsWith(const std::vector<std::string>& parts, const std::vector<std::string>& prefix) {
  return parts.size() >= prefix.size() && std::equal(prefix.begin(), prefix.end(), parts.begin());
}

// Opens folder `part` of `at` without following a link; -1 with errno on failure.
int openPart(int at, const std::string& part) {
  return openat(at, part.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
}

}  // namespace

ConfinedFolder::ConfinedFolder(const std::string& root, std::string rootName)
    : root_(root), rootName_(std::move(rootName)) {
  fd_ = FileDescriptor(open(root.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (!fd_.valid()) throw Error(root + ": cannot open the folder: " + std::strerror(errno));
  std::error_code ec;
  canonical_ = std::filesystem::canonical(root, ec).string();
}

std::string ConfinedFolder::resolve(const std::string& request) const {
  const std::string beneath = " beneath " + rootName_ + " " + root_;
  auto refuse = [&](const std::string& problem) {
    return Error("'" + shown(request) + "': " + problem);
  };
  // Names with control characters would carry terminal escapes into logs and listings.
  if (std::any_of(request.begin(), request.end(), isControl))
    throw refuse("a control character is not allowed" + beneath);
  std::vector<std::string> parts = partsOf(request);
  for (const std::string& part : parts) {
    if (part == "..") throw refuse("'..' is not allowed" + beneath);
    if (part.size() > NAME_MAX)
      throw refuse("a part longer than " + std::to_string(NAME_MAX) + " bytes" + beneath);
  }
  if (!request.empty() && request.front() == '/') {
    const std::vector<std::string> spelled =
        partsOf(std::filesystem::absolute(root_).lexically_normal().string());
    const std::vector<std::string> canonical = partsOf(canonical_);
    const std::vector<std::string>* inside = startsWith(parts, spelled)     ? &spelled
                                             : startsWith(parts, canonical) ? &canonical
                                                                            : nullptr;
    if (!inside) throw refuse("outside " + rootName_ + " " + root_);
    parts.erase(parts.begin(), parts.begin() + static_cast<std::ptrdiff_t>(inside->size()));
  }
  if (parts.size() > kMaxDepth)
    throw refuse("more than " + std::to_string(kMaxDepth) + " folders deep" + beneath);
  // The parts that exist must be folders, none a link; the rest is made at the first capture.
  FileDescriptor at(fcntl(fd_.get(), F_DUPFD_CLOEXEC, 0));
  std::size_t existing = 0;
  for (; existing < parts.size(); ++existing) {
    const int next = openPart(at.get(), parts[existing]);
    if (next < 0 && errno == ENOENT) break;
    if (next < 0) {
      const int error = errno;
      struct stat st {};
      const std::string here = "'" + shown(joined(parts, existing + 1)) + "'";
      if (fstatat(at.get(), parts[existing].c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0) {
        if (S_ISLNK(st.st_mode))
          throw refuse(here + " is a symbolic link, and none is followed" + beneath);
        if (!S_ISDIR(st.st_mode)) throw refuse(here + " is not a folder" + beneath);
      }
      throw refuse("cannot open " + here + beneath + ": " + std::strerror(error));
    }
    at = FileDescriptor(next);
  }
  if (faccessat(at.get(), ".", W_OK | X_OK, AT_EACCESS) != 0)
    throw refuse("cannot create files in '" + shown(joined(parts, existing)) + "'" + beneath +
                 ": " + std::strerror(errno));
  return joined(parts, parts.size());
}

FileDescriptor ConfinedFolder::openFolder(const std::string& relative, bool create) const {
  const std::vector<std::string> parts = partsOf(relative);
  FileDescriptor at(fcntl(fd_.get(), F_DUPFD_CLOEXEC, 0));
  if (!at.valid()) throw Error(root_ + ": cannot open the folder: " + std::strerror(errno));
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string here = "'" + joined(parts, i + 1) + "' beneath " + rootName_ + " " + root_;
    if (parts[i] == "..") throw Error(here + ": '..' is not allowed");
    int next = openPart(at.get(), parts[i]);
    if (next < 0 && errno == ENOENT && create) {
      if (mkdirat(at.get(), parts[i].c_str(), 0777) != 0 && errno != EEXIST)
        throw Error(here + ": cannot create the folder: " + std::strerror(errno));
      next = openPart(at.get(), parts[i]);
    }
    if (next < 0) {
      const int error = errno;
      struct stat st {};
      if (fstatat(at.get(), parts[i].c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISLNK(st.st_mode))
        throw Error(here + ": is a symbolic link, and none is followed");
      throw Error(here + ": cannot open the folder: " + std::strerror(error));
    }
    at = FileDescriptor(next);
  }
  return at;
}

}  // namespace base
