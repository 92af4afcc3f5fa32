// A folder nothing is written outside of (base/ConfinedFolder.h), on real folders and links in a
// scratch folder: requests are taken inside the root or refused with a message naming it, nothing
// is created by resolving, and a link swapped in after a request was checked still leads nowhere.
#include "base/ConfinedFolder.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "base/Error.h"

namespace dfb {
namespace {

namespace fs = std::filesystem;

class ConfinedFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scratch_ = fs::path(::testing::TempDir()) /
               ("confined-folder-" +
                std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(scratch_);
    fs::create_directories(root_ = scratch_ / "root");
    fs::create_directories(outside_ = scratch_ / "outside");
  }
  void TearDown() override { fs::remove_all(scratch_); }

  // The message of the refusal of `request`, or a failure when it was taken.
  std::string refusal(const base::ConfinedFolder& folder, const std::string& request) {
    try {
      const std::string taken = folder.resolve(request);
      ADD_FAILURE() << "'" << request << "' was taken as '" << taken << "'";
    } catch (const base::Error& e) {
      return e.what();
    }
    return {};
  }
  bool empty(const fs::path& folder) const { return fs::is_empty(folder); }

  fs::path scratch_, root_, outside_;
};

TEST_F(ConfinedFolderTest, RelativeRequestsAreTakenInsideTheRootAndNothingIsCreated) {
  const base::ConfinedFolder folder(root_.string(), "the capture root");
  EXPECT_EQ(folder.resolve("jobs/a"), "jobs/a");
  EXPECT_EQ(folder.resolve("./jobs//a/"), "jobs/a");
  EXPECT_EQ(folder.resolve("."), "");
  EXPECT_TRUE(empty(root_)) << "resolving makes no folder";
  fs::create_directories(root_ / "jobs");
  EXPECT_EQ(folder.resolve("jobs/b/c"), "jobs/b/c") << "missing parts are made later";
  EXPECT_EQ(fs::directory_iterator(root_ / "jobs"), fs::directory_iterator());
}

TEST_F(ConfinedFolderTest, AbsoluteRequestsMustLieInTheRoot) {
  // The root given through a link: either spelling of an absolute path inside it is taken.
  fs::create_directory_symlink(root_, scratch_ / "root-link");
  const base::ConfinedFolder folder((scratch_ / "root-link").string(), "the capture root");
  EXPECT_EQ(folder.resolve((scratch_ / "root-link" / "a").string()), "a");
  EXPECT_EQ(folder.resolve((root_ / "b" / "c").string()), "b/c");
  EXPECT_EQ(folder.resolve(root_.string() + "/"), "");
  const std::string elsewhere = (outside_ / "x").string();
  EXPECT_EQ(refusal(folder, elsewhere),
            "'" + elsewhere + "': outside the capture root " + (scratch_ / "root-link").string());
  // A prefix of the root's name is not the root.
  EXPECT_NE(refusal(folder, root_.string() + "-sibling/x"), "");
  EXPECT_TRUE(empty(outside_));
}

TEST_F(ConfinedFolderTest, DotDotIsRefusedEvenWhereItWouldStayInside) {
  const base::ConfinedFolder folder(root_.string(), "the capture root");
  const std::string beneath = " beneath the capture root " + root_.string();
  EXPECT_EQ(refusal(folder, "../x"), "'../x': '..' is not allowed" + beneath);
  EXPECT_EQ(refusal(folder, "a/../b"), "'a/../b': '..' is not allowed" + beneath);
  EXPECT_EQ(refusal(folder, (root_ / ".." / "outside").string()),
            "'" + (root_ / ".." / "outside").string() + "': '..' is not allowed" + beneath);
  EXPECT_EQ(refusal(folder, std::string("a\0b", 3)),
            "'a?b': a control character is not allowed" + beneath)
      << "bytes from the wire are shown printable";
  EXPECT_EQ(refusal(folder, "red\x1b[31m"),
            "'red?[31m': a control character is not allowed" + beneath);
  std::string deep;
  for (int i = 0; i < 65; ++i) deep += "d/";
  EXPECT_EQ(refusal(folder, deep), "'" + deep + "': more than 64 folders deep" + beneath);
  const std::string huge(300, 'x');
  EXPECT_EQ(refusal(folder, "../" + huge),
            "'../" + huge.substr(0, 197) + "...': '..' is not allowed" + beneath);
}

TEST_F(ConfinedFolderTest, LinksAndFilesOnTheWayAreRefused) {
  const base::ConfinedFolder folder(root_.string(), "the capture root");
  const std::string beneath = " beneath the capture root " + root_.string();
  fs::create_directory_symlink(outside_, root_ / "out");
  EXPECT_EQ(refusal(folder, "out/x"),
            "'out/x': 'out' is a symbolic link, and none is followed" + beneath);
  EXPECT_EQ(refusal(folder, "out"),
            "'out': 'out' is a symbolic link, and none is followed" + beneath);
  // A link that stays inside is refused too: links are not weighed, they are not followed.
  fs::create_directories(root_ / "real");
  fs::create_directory_symlink(root_ / "real", root_ / "real" / "again");
  EXPECT_EQ(refusal(folder, "real/again/x"),
            "'real/again/x': 'real/again' is a symbolic link, and none is followed" + beneath);
  { std::ofstream(root_ / "file") << "x"; }
  EXPECT_EQ(refusal(folder, "file/x"), "'file/x': 'file' is not a folder" + beneath);
  EXPECT_TRUE(empty(outside_));
}

TEST_F(ConfinedFolderTest, OpenFolderMakesWhatIsMissingWithTheUmasksMode) {
  const base::ConfinedFolder folder(root_.string(), "the capture root");
  const mode_t before = umask(027);
  base::FileDescriptor at = folder.openFolder("jobs/a/r0c0", true);
  umask(before);
  EXPECT_TRUE(at.valid());
  EXPECT_TRUE(fs::is_directory(root_ / "jobs" / "a" / "r0c0"));
  struct stat st {};
  ASSERT_EQ(stat((root_ / "jobs").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0750u);
  EXPECT_THROW(folder.openFolder("not/made", false), base::Error);
  EXPECT_FALSE(fs::exists(root_ / "not"));
}

// The race a check alone loses: the request is checked while its folder is missing, then a link
// to elsewhere is put where the folder would go. Making the folders refuses the link.
TEST_F(ConfinedFolderTest, ALinkSwappedInAfterTheCheckLeadsNowhere) {
  const base::ConfinedFolder folder(root_.string(), "the capture root");
  EXPECT_EQ(folder.resolve("job/r0c0"), "job/r0c0");
  fs::create_directory_symlink(outside_, root_ / "job");
  try {
    folder.openFolder("job/r0c0", true);
    ADD_FAILURE() << "made a folder through a link";
  } catch (const base::Error& e) {
    EXPECT_EQ(std::string(e.what()), "'job' beneath the capture root " + root_.string() +
                                         ": is a symbolic link, and none is followed");
  }
  EXPECT_TRUE(empty(outside_));
}

TEST_F(ConfinedFolderTest, AMissingRootIsAnErrorNamingIt) {
  const std::string missing = (scratch_ / "no-such-root").string();
  try {
    base::ConfinedFolder folder(missing, "the capture root");
    ADD_FAILURE() << "opened a missing root";
  } catch (const base::Error& e) {
    EXPECT_EQ(std::string(e.what()),
              missing + ": cannot open the folder: No such file or directory");
  }
}

}  // namespace
}  // namespace dfb
