// AtomicFile's rule for an output path: regular files (also behind symlinks) are replaced
// whole; character devices and FIFOs are written in place and stay what they are; other
// kinds, "" and directories are usage errors. Device nodes are made in a temporary folder.
#include "thermodrift/io/atomic_file.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <string>

#include "../../support/special_files.hpp"
#include "../../support/temp_dir.hpp"
#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

namespace fs = std::filesystem;
using testing::file_type;
using testing::read_file;
using testing::TempDir;

// More than a pipe's buffer, so that a FIFO writer must wait for its reader.
std::string large_text() {
  std::string text;
  for (int row = 0; text.size() < 300000; ++row) text += std::to_string(row) + ",1.25,-0.5\n";
  return text;
}

TEST(AtomicFile, ReplacesARegularFileWholeAndLeavesNoTemporary) {
  TempDir dir;
  const std::string path = dir.write("out.csv", "old\n");
  write_file_atomically(path, "new\n");
  EXPECT_EQ(read_file(path), "new\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.csv"});
}

TEST(AtomicFile, UncommittedLeavesTheOldFile) {
  TempDir dir;
  const std::string path = dir.write("out.csv", "old\n");
  {
    AtomicFile file(path);
    file.stream() << "half";
  }
  EXPECT_EQ(read_file(path), "old\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.csv"});
}

// A replaced file keeps its permissions (they were reset to 0644); a new one gets 0644.
TEST(AtomicFile, AReplacedFileKeepsItsPermissions) {
  TempDir dir;
  const std::string path = dir.write("out.csv", "old\n");
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  write_file_atomically(path, "new\n");
  EXPECT_EQ(read_file(path), "new\n");
  EXPECT_EQ(fs::status(path).permissions(), fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  write_file_atomically(dir.file("fresh.csv"), "new\n");
  EXPECT_EQ(fs::status(dir.file("fresh.csv")).permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read);
}

// Renaming needs only the folder's permission, so a model its owner made read-only was
// replaced. It is kept now, with an error. Root may write any file (as `cp` does), so the
// write runs in a child that drops to nobody when the tests run as root.
TEST(AtomicFile, AReadOnlyFileIsKept) {
  TempDir dir;
  const std::string path = dir.write("model.json", "old\n");
  fs::permissions(path, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  fs::permissions(dir.path(), fs::perms::all);  // the folder is writable by the child
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) ::_exit(3);
    try {
      write_file_atomically(path, "new\n");
      ::_exit(1);
    } catch (const Error& error) {
      ::_exit(std::string(error.what()).find("the file is read-only") != std::string::npos ? 0 : 2);
    } catch (...) {
      ::_exit(4);
    }
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: replaced, 2: another error, 3: could not drop to nobody";
  EXPECT_EQ(read_file(path), "old\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"model.json"});
}

TEST(AtomicFile, WritesIntoANullDeviceAndLeavesItADevice) {
  TempDir dir;
  const std::string device = dir.file("null");
  if (const auto why = testing::make_memory_device(device, testing::kNullMinor); !why.empty()) GTEST_SKIP() << why;
  AtomicFile file(device);
  EXPECT_TRUE(file.in_place());
  file.stream() << large_text();
  file.commit();
  EXPECT_EQ(file_type(device), S_IFCHR);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"null"});
}

TEST(AtomicFile, AFullDeviceIsAWriteErrorAndStaysADevice) {
  TempDir dir;
  const std::string device = dir.file("full");
  if (const auto why = testing::make_memory_device(device, testing::kFullMinor); !why.empty()) GTEST_SKIP() << why;
  AtomicFile file(device);
  file.stream() << "a model\n";
  try {
    file.commit();
    FAIL() << "writing a full device succeeded";
  } catch (const UsageError& e) {
    FAIL() << "a write error is not a usage error: " << e.what();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOSPC)), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
  EXPECT_EQ(file_type(device), S_IFCHR);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"full"});
}

TEST(AtomicFile, AFifoGetsTheWholeOutputAndStaysAFifo) {
  TempDir dir;
  const std::string fifo = dir.file("pipe");
  testing::make_fifo(fifo);
  const std::string text = large_text();
  testing::FifoReader reader(fifo);
  {
    AtomicFile file(fifo);
    file.stream() << text;
    file.commit();
  }
  EXPECT_EQ(reader.finish(), text);
  EXPECT_EQ(file_type(fifo), S_IFIFO);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"pipe"});
}

TEST(AtomicFile, ASymlinkStaysALinkAndItsTargetIsReplaced) {
  TempDir dir;
  fs::create_directories(dir.path() / "data");
  fs::create_directories(dir.path() / "links");
  const std::string target = dir.write("data/out.csv", "old\n");
  const std::string link = dir.file("links/out.csv");
  fs::create_symlink("../data/out.csv", link);  // relative: read against the link's folder
  write_file_atomically(link, "new\n");
  EXPECT_EQ(file_type(link), S_IFLNK);
  EXPECT_EQ(fs::read_symlink(link), fs::path("../data/out.csv"));
  EXPECT_EQ(read_file(target), "new\n");
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"data", "links"}));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path() / "data"), fs::directory_iterator()), 1);
}

TEST(AtomicFile, AChainOfLinksIsFollowedToTheLastTarget) {
  TempDir dir;
  const std::string target = dir.write("out.csv", "old\n");
  fs::create_symlink("out.csv", dir.file("second"));
  fs::create_symlink(dir.file("second"), dir.file("first"));
  write_file_atomically(dir.file("first"), "new\n");
  EXPECT_EQ(file_type(dir.file("first")), S_IFLNK);
  EXPECT_EQ(file_type(dir.file("second")), S_IFLNK);
  EXPECT_EQ(read_file(target), "new\n");
}

TEST(AtomicFile, ADanglingSymlinkGetsItsTargetCreated) {
  TempDir dir;
  fs::create_directories(dir.path() / "data");
  const std::string link = dir.file("out.csv");
  fs::create_symlink("data/new.csv", link);
  write_file_atomically(link, "new\n");
  EXPECT_EQ(file_type(link), S_IFLNK);
  EXPECT_EQ(read_file(dir.file("data/new.csv")), "new\n");
}

TEST(AtomicFile, ALinkIntoAFifoWritesTheFifo) {
  TempDir dir;
  const std::string fifo = dir.file("pipe");
  testing::make_fifo(fifo);
  fs::create_symlink("pipe", dir.file("link"));
  testing::FifoReader reader(fifo);
  write_file_atomically(dir.file("link"), "through the link\n");
  EXPECT_EQ(reader.finish(), "through the link\n");
  EXPECT_EQ(file_type(dir.file("link")), S_IFLNK);
  EXPECT_EQ(file_type(fifo), S_IFIFO);
}

TEST(AtomicFile, ASymlinkLoopIsAUsageError) {
  TempDir dir;
  fs::create_symlink("b", dir.file("a"));
  fs::create_symlink("a", dir.file("b"));
  EXPECT_THROW(write_file_atomically(dir.file("a"), "x"), UsageError);
  EXPECT_EQ(file_type(dir.file("a")), S_IFLNK);
}

TEST(AtomicFile, AnEmptyPathAndADirectoryAreUsageErrors) {
  TempDir dir;
  EXPECT_THROW(write_file_atomically("", "x"), UsageError);
  EXPECT_THROW(write_file_atomically(dir.path().string(), "x"), UsageError);
  fs::create_symlink(dir.path(), dir.file("folder-link"));
  EXPECT_THROW(write_file_atomically(dir.file("folder-link"), "x"), UsageError);
}

TEST(AtomicFile, ASocketIsRefusedByName) {
  TempDir dir;
  const std::string path = dir.file("socket");
  const int endpoint = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(endpoint, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (path.size() >= sizeof address.sun_path) GTEST_SKIP() << "temporary path too long for a socket";
  std::strcpy(address.sun_path, path.c_str());
  ASSERT_EQ(::bind(endpoint, reinterpret_cast<const sockaddr*>(&address), sizeof address), 0);
  try {
    write_file_atomically(path, "x");
    ADD_FAILURE() << "wrote into a socket";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("socket"), std::string::npos) << e.what();
  }
  ::close(endpoint);
  EXPECT_EQ(file_type(path), S_IFSOCK);
}

TEST(AtomicFile, ABlockDeviceIsRefused) {
  TempDir dir;
  const std::string path = dir.file("disk");
  // Never opened: the rule refuses it after stat().
  if (::mknod(path.c_str(), S_IFBLK | 0600, makedev(7, 0)) != 0) {
    GTEST_SKIP() << "cannot make a device node (" << std::strerror(errno) << ")";
  }
  try {
    write_file_atomically(path, "x");
    ADD_FAILURE() << "wrote into a block device";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("block device"), std::string::npos) << e.what();
  }
  EXPECT_EQ(file_type(path), S_IFBLK);
}

TEST(AtomicFile, AnInputIsRefusedAlsoThroughASymlink) {
  TempDir dir;
  const std::string input = dir.write("log.csv", "data\n");
  fs::create_symlink("log.csv", dir.file("out.csv"));
  EXPECT_THROW(write_file_atomically(dir.file("out.csv"), "x", {input}), UsageError);
  EXPECT_THROW(write_file_atomically(input, "x", {dir.file("out.csv")}), UsageError);
  EXPECT_EQ(read_file(input), "data\n");
  EXPECT_EQ(file_type(dir.file("out.csv")), S_IFLNK);
}

TEST(AtomicFile, OutputFolderMustBeAFolder) {
  TempDir dir;
  EXPECT_THROW(check_output_folder(""), UsageError);
  EXPECT_THROW(check_output_folder(dir.write("file", "x")), UsageError);
  EXPECT_NO_THROW(check_output_folder(dir.path().string()));
  EXPECT_NO_THROW(check_output_folder(dir.file("not-yet")));
}

// Writes a report-like tree (a file and one in a subfolder) into the staging folder.
void stage_two_files(const StagedFolder& out) {
  fs::create_directory(fs::path(out.staging()) / "figures");
  write_file_atomically((fs::path(out.staging()) / "report.html").string(), "new page");
  write_file_atomically((fs::path(out.staging()) / "figures" / "raw.dat").string(), "1 2\n");
}

TEST(StagedFolder, NewFolderAppearsWholeOnCommitAndNotAtAllWithout) {
  TempDir dir;
  {
    StagedFolder out(dir.file("report/"));
    stage_two_files(out);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{fs::path(out.staging()).filename().string()});
  }
  EXPECT_TRUE(dir.entries().empty()) << "no commit: nothing left";
  StagedFolder out(dir.file("report"));
  stage_two_files(out);
  EXPECT_EQ(out.committed_path((fs::path(out.staging()) / "figures" / "raw.dat").string()),
            (dir.path() / "report" / "figures" / "raw.dat").string());
  out.commit();
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"report"});
  EXPECT_EQ(read_file(dir.file("report/report.html")), "new page");
  EXPECT_EQ(read_file(dir.file("report/figures/raw.dat")), "1 2\n");
}

// A process ended by a second Ctrl-C or a kill runs no destructor and leaves its staging
// folder; the next run into the same folder removes it. One of a process still running
// (this one), and one of another folder's name, are left alone.
TEST(StagedFolder, StagingFoldersOfEndedProcessesAreRemovedByTheNextRun) {
  TempDir dir;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);  // reaped: its pid runs nothing now
  const std::string ended = fmt::format(".report.partial-{}-0", child);
  const std::string running = fmt::format(".report.partial-{}-7", ::getpid());
  const std::string other = fmt::format(".other.partial-{}-0", child);
  const std::string nested = fmt::format(".{}.partial-{}-0", ended, child);  // demo's report, staged in its own
  for (const auto& name : {ended, running, other, nested}) {
    fs::create_directory(dir.path() / name);
    dir.write(name + "/report.html", "half");
  }
  StagedFolder out(dir.file("report"));
  const auto entries = dir.entries();
  EXPECT_EQ(std::count(entries.begin(), entries.end(), ended), 0);
  EXPECT_EQ(std::count(entries.begin(), entries.end(), nested), 0);
  EXPECT_EQ(std::count(entries.begin(), entries.end(), running), 1);
  EXPECT_EQ(std::count(entries.begin(), entries.end(), other), 1);
}

// An empty file (gnuplot's log when all went well) is copied into an existing folder as an
// empty file; the copy used to fail (a stream that inserts nothing sets failbit), which
// failed every report into an existing folder, and the demo, whose report stages inside it.
TEST(StagedFolder, EmptyFilesReachAnExistingFolder) {
  TempDir dir;
  fs::create_directory(dir.path() / "report");
  StagedFolder out(dir.file("report"));
  fs::create_directory(fs::path(out.staging()) / "figures");
  write_file_atomically((fs::path(out.staging()) / "figures" / "gnuplot.log").string(), "");
  out.commit();
  EXPECT_TRUE(fs::exists(dir.path() / "report" / "figures" / "gnuplot.log"));
  EXPECT_EQ(read_file(dir.file("report/figures/gnuplot.log")), "");
}

TEST(StagedFolder, ExistingFolderGetsItsFilesReplacedAndKeepsTheOthers) {
  TempDir dir;
  fs::create_directory(dir.path() / "report");
  dir.write("report/report.html", "old page");
  dir.write("report/notes.txt", "mine");
  {
    StagedFolder out(dir.file("report"));
    stage_two_files(out);
  }
  EXPECT_EQ(read_file(dir.file("report/report.html")), "old page") << "no commit: the folder as it was";
  EXPECT_FALSE(fs::exists(dir.path() / "report" / "figures"));
  StagedFolder out(dir.file("report"));
  stage_two_files(out);
  out.commit();
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"report"}) << "the staging folder is gone";
  EXPECT_EQ(read_file(dir.file("report/report.html")), "new page");
  EXPECT_EQ(read_file(dir.file("report/notes.txt")), "mine");
  EXPECT_EQ(read_file(dir.file("report/figures/raw.dat")), "1 2\n");
  EXPECT_THROW(StagedFolder(dir.file("report/notes.txt")), UsageError);
}

}  // namespace
}  // namespace thermodrift
