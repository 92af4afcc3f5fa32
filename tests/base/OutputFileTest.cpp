// Files written in place (base/OutputFile.h), on real files in a scratch folder: appended or
// truncated, with the umask's mode, and never through a symbolic link at their own name.
#include "base/OutputFile.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "base/Error.h"

namespace dfb {
namespace {

namespace fs = std::filesystem;

class OutputFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::path(::testing::TempDir()) /
              ("output-file-" +
               std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }
  std::string path(const std::string& name) const { return (folder_ / name).string(); }
  static std::string read(const std::string& path) {
    std::stringstream bytes;
    bytes << std::ifstream(path).rdbuf();
    return bytes.str();
  }
  static void write(const base::FileDescriptor& fd, const std::string& bytes) {
    ASSERT_EQ(::write(fd.get(), bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }

  fs::path folder_;
};

TEST_F(OutputFileTest, AppendKeepsWhatIsThereTruncateDoesNot) {
  const std::string target = path("stats.jsonl");
  { std::ofstream(target) << "old\n"; }
  write(base::openOutputFile(target, true), "appended\n");
  EXPECT_EQ(read(target), "old\nappended\n");
  write(base::openOutputFile(target, false), "fresh\n");
  EXPECT_EQ(read(target), "fresh\n");
  std::FILE* stream = base::openOutputStream(target, true);
  ASSERT_NE(stream, nullptr);
  std::fputs("streamed\n", stream);
  std::fclose(stream);
  EXPECT_EQ(read(target), "fresh\nstreamed\n");
}

TEST_F(OutputFileTest, TheModeIsWhatTheUmaskLeaves) {
  for (const mode_t mask : {mode_t{027}, mode_t{077}}) {
    const mode_t before = umask(mask);
    const std::string target = path("out-" + std::to_string(mask));
    base::openOutputFile(target, false);
    umask(before);
    struct stat st {};
    ASSERT_EQ(stat(target.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0666u & ~mask) << "umask " << std::oct << mask;
  }
}

TEST_F(OutputFileTest, ALinkAtItsNameIsRefusedAndWhatItPointsToIsUntouched) {
  const std::string victim = path("victim");
  { std::ofstream(victim) << "precious"; }
  const std::string target = path("stats.jsonl");
  fs::create_symlink(victim, target);
  for (const bool append : {true, false}) {
    try {
      base::openOutputFile(target, append);
      ADD_FAILURE() << "opened through a symbolic link";
    } catch (const base::Error& e) {
      EXPECT_EQ(std::string(e.what()), target + ": is a symbolic link; outputs never follow one");
    }
  }
  EXPECT_EQ(read(victim), "precious");
  const std::string missing = path("no-such-folder/stats.jsonl");
  EXPECT_THROW(base::openOutputFile(missing, true), base::Error);
}

}  // namespace
}  // namespace dfb
