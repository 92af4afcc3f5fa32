// Output files never seen half-written (base/AtomicFile.h), on real files in a scratch folder:
// the target holds its old bytes (or is absent) until commit, then all the new ones; nothing is
// left behind either way; failures name the path and the reason.
#include "base/AtomicFile.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/Error.h"

namespace dfb {
namespace {

namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::path(::testing::TempDir()) /
              ("atomic-file-" +
               std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  std::string path(const std::string& name) const { return (folder_ / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(folder_)) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }
  static std::string read(const std::string& path) {
    std::string bytes(fs::file_size(path), '\0');
    std::ifstream(path, std::ios::binary)
        .read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return bytes;
  }
  static void write(base::AtomicFile& file, const std::string& bytes) {
    ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), file.stream()), bytes.size());
  }

  fs::path folder_;
};

TEST_F(AtomicFileTest, TheTargetAppearsWholeOnlyAtCommit) {
  const std::string target = path("stats.json");
  std::string bytes(100000, 'x');
  bytes += "end";
  {
    base::AtomicFile file(target);
    write(file, bytes);
    // Before commit: no target, one hidden temporary next to where it will be.
    EXPECT_FALSE(fs::exists(target));
    const std::vector<std::string> names = entries();
    ASSERT_EQ(names.size(), 1u);
    EXPECT_EQ(names[0].rfind(".stats.json.", 0), 0u) << names[0];
    EXPECT_EQ(names[0].size(), std::string(".stats.json.XXXXXX").size());
    file.commit();
  }
  EXPECT_EQ(read(target), bytes);
  EXPECT_EQ(entries(), std::vector<std::string>{"stats.json"});
}

// 0666 less the umask, as any file the user's programs create: the operator decides who reads.
TEST_F(AtomicFileTest, TheModeIsWhatTheUmaskLeaves) {
  for (const mode_t mask : {mode_t{022}, mode_t{027}, mode_t{077}}) {
    const mode_t before = umask(mask);
    const std::string target = path("out-" + std::to_string(mask) + ".png");
    {
      base::AtomicFile file(target);
      write(file, "bytes");
      file.commit();
    }
    umask(before);
    struct stat st {};
    ASSERT_EQ(stat(target.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0666u & ~mask) << "umask " << std::oct << mask;
  }
}

// A link planted at the target's name would send the output wherever it points: it is an error,
// and neither the link nor what it points to changes.
TEST_F(AtomicFileTest, ALinkAtTheTargetsNameIsRefusedNotFollowed) {
  const std::string victim = path("victim.txt");
  { std::ofstream(victim) << "precious"; }
  const std::string target = path("frame.png");
  fs::create_symlink(victim, target);
  base::AtomicFile file(target);
  write(file, "attacker's choice");
  try {
    file.commit();
    ADD_FAILURE() << "committed through a symbolic link";
  } catch (const base::Error& e) {
    EXPECT_EQ(std::string(e.what()),
              target + ": is a symbolic link; outputs never follow or replace one");
  }
  EXPECT_EQ(read(victim), "precious");
  EXPECT_TRUE(fs::is_symlink(target));
  EXPECT_EQ(entries(), (std::vector<std::string>{"frame.png", "victim.txt"}));
}

// The folder-descriptor form writes into the folder it was given, whatever its path is later.
TEST_F(AtomicFileTest, AFolderDescriptorAndANameWriteThere) {
  fs::create_directories(folder_ / "sub");
  const int at = open((folder_ / "sub").c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  ASSERT_GE(at, 0);
  fs::rename(folder_ / "sub", folder_ / "moved");
  {
    base::AtomicFile file(at, "x.txt", "shown/x.txt");
    write(file, "in the folder held open");
    file.commit();
  }
  close(at);
  EXPECT_EQ(read(path("moved/x.txt")), "in the folder held open");
}

TEST_F(AtomicFileTest, AnExistingFileKeepsItsBytesUntilCommitThenHasOnlyTheNewOnes) {
  const std::string target = path("frame.png");
  { std::ofstream(target) << "the old file, longer than the new one"; }
  base::AtomicFile file(target);
  write(file, "new");
  EXPECT_EQ(read(target), "the old file, longer than the new one");
  file.commit();
  EXPECT_EQ(read(target), "new");
}

TEST_F(AtomicFileTest, WithoutCommitNothingChangesAndTheTemporaryGoes) {
  const std::string kept = path("kept.txt");
  { std::ofstream(kept) << "old"; }
  {
    base::AtomicFile file(kept);
    write(file, "half of somethi");
  }  // e.g. an exception while writing
  {
    base::AtomicFile file(path("never.txt"));
    write(file, "never committed");
  }
  EXPECT_EQ(read(kept), "old");
  EXPECT_EQ(entries(), std::vector<std::string>{"kept.txt"});
}

TEST_F(AtomicFileTest, TwoWritersOfOneTargetDoNotShareATemporary) {
  const std::string target = path("same.txt");
  base::AtomicFile first(target), second(target);
  write(first, "first");
  write(second, "second");
  EXPECT_EQ(entries().size(), 2u);
  first.commit();
  second.commit();
  EXPECT_EQ(read(target), "second");  // the last commit wins, whole
  EXPECT_EQ(entries(), std::vector<std::string>{"same.txt"});
}

TEST_F(AtomicFileTest, FailuresNameThePathAndTheReason) {
  const std::string missing = path("no-such-folder/out.png");
  try {
    base::AtomicFile file(missing);
    ADD_FAILURE() << "created a file in a missing folder";
  } catch (const base::Error& e) {
    EXPECT_EQ(std::string(e.what()),
              missing + ": cannot create a temporary file: No such file or directory");
  }
  // The rename fails (a folder is in the way): commit throws and removes the temporary.
  const std::string folder = path("a-folder");
  fs::create_directories(fs::path(folder) / "inside");
  base::AtomicFile file(folder);
  write(file, "bytes");
  try {
    file.commit();
    ADD_FAILURE() << "committed over a folder";
  } catch (const base::Error& e) {
    EXPECT_EQ(std::string(e.what()), folder + ": cannot write: Is a directory");
  }
  EXPECT_EQ(entries(), std::vector<std::string>{"a-folder"});
}

TEST_F(AtomicFileTest, CheckWritableFolderMakesTheFolderOrSaysWhy) {
  const std::string nested = path("a/b/c");
  EXPECT_EQ(base::checkWritableFolder(nested), "");
  EXPECT_TRUE(fs::is_directory(nested));
  EXPECT_TRUE(fs::is_empty(nested)) << "the probe file is removed";
  EXPECT_EQ(base::checkWritableFolder(nested), "") << "an existing folder is fine";
  { std::ofstream(path("a-file")) << "x"; }
  const std::string underFile = path("a-file/sub");
  EXPECT_EQ(base::checkWritableFolder(underFile),
            underFile + ": cannot create the folder: Not a directory");
  // /proc refuses new files even to root.
  const std::string proc = "/proc/self/dfbwall-probe-folder";
  const std::string problem = base::checkWritableFolder(proc);
  EXPECT_EQ(problem.rfind(proc + ": cannot create the folder: ", 0), 0u) << problem;
}

}  // namespace
}  // namespace dfb
