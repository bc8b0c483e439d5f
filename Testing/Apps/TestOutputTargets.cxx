// Where a set of files may go besides regular files (Apps/Tools/AtomicFile.h): a FIFO or a
// character device named as an output is written through and stays what it was, anything else
// that is not a regular file is refused before a byte is written; files a set removes go in the
// same commit as its new members; a set of many files in one folder holds one descriptor of it;
// a movie can be a member of a larger set.
#include "AtomicFile.h"
#include "MovieWriter.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkUnsignedCharArray.h"

#include <vtksys/SystemTools.hxx>

#include <gtest/gtest.h>

#include <dirent.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace asrt::tools;
using vtksys::SystemTools;

namespace
{
std::string scratch(const std::string& name)
{
  const std::string dir = std::string(ASRT_TEST_OUTPUT_DIR) + "/" + name;
  SystemTools::RemoveADirectory(dir);
  SystemTools::MakeDirectory(dir);
  return dir;
}

std::string contentOf(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const std::string& path, const std::string& text)
{
  std::ofstream(path, std::ios::binary) << text;
}

/// The names in `dir`, hidden ones included.
std::vector<std::string> namesIn(const std::string& dir)
{
  std::vector<std::string> names;
  if (DIR* d = opendir(dir.c_str()))
  {
    while (const dirent* e = readdir(d))
      if (std::strcmp(e->d_name, ".") != 0 && std::strcmp(e->d_name, "..") != 0)
        names.emplace_back(e->d_name);
    closedir(d);
  }
  return names;
}

mode_t typeOf(const std::string& path)
{
  struct stat st;
  return lstat(path.c_str(), &st) == 0 ? (st.st_mode & S_IFMT) : 0;
}

std::size_t openDescriptors()
{
  return namesIn("/proc/self/fd").size();
}

/// The message of what `f` throws, or "" if it throws nothing.
template<class F>
std::string errorOf(F&& f)
{
  try
  {
    f();
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return std::string();
}

/// Everything a FIFO's reader can read now (it was opened non-blocking).
std::string drain(int fd)
{
  std::string out;
  char buffer[4096];
  ssize_t n;
  while ((n = read(fd, buffer, sizeof buffer)) > 0)
    out.append(buffer, static_cast<std::size_t>(n));
  return out;
}
}

TEST(OutputTargets, AFifoIsWrittenThroughAtTheCommitAndStaysAFifo)
{
  const std::string dir = scratch("target-fifo");
  const std::string fifo = dir + "/out.png";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  writeText(dir + "/b.txt", "old b");
  // The reader is there first (without it the FIFO is refused); the bytes fit in the pipe.
  const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(reader, 0);
  {
    AtomicFileSet files;
    TemporaryFile& through = files.add(fifo);
    EXPECT_TRUE(through.writesThrough());
    through.write("picture", 7);
    files.add(dir + "/b.txt").write("new b", 5);
    EXPECT_EQ(drain(reader), "") << "bytes went through before the commit";
    files.commit();
  }
  EXPECT_EQ(drain(reader), "picture");
  close(reader);
  EXPECT_EQ(typeOf(fifo), mode_t(S_IFIFO)) << "the FIFO was replaced";
  EXPECT_EQ(contentOf(dir + "/b.txt"), "new b");
  EXPECT_EQ(namesIn(dir).size(), 2u) << "a temporary was left";
}

TEST(OutputTargets, AFifoNobodyReadsIsRefusedAtOnce)
{
  const std::string dir = scratch("target-fifo-no-reader");
  const std::string fifo = dir + "/out.png";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  AtomicFileSet files;
  const std::string message = errorOf([&] { files.add(fifo); });
  EXPECT_NE(message.find("no process is reading"), std::string::npos) << message;
  EXPECT_NE(message.find(fifo), std::string::npos) << message;
  EXPECT_EQ(typeOf(fifo), mode_t(S_IFIFO));
  EXPECT_EQ(namesIn(dir).size(), 1u);
}

TEST(OutputTargets, AReaderGoneIsAnErrorAndTheRestOfTheSetStaysOld)
{
  const std::string dir = scratch("target-fifo-gone");
  const std::string fifo = dir + "/out.png";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  writeText(dir + "/b.txt", "old b");
  const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(reader, 0);
  AtomicFileSet files;
  files.add(fifo).write("picture", 7);
  files.add(dir + "/b.txt").write("new b", 5);
  close(reader);
  // EPIPE, not death by SIGPIPE.
  const std::string message = errorOf([&] { files.commit(); });
  EXPECT_NE(message.find(std::strerror(EPIPE)), std::string::npos) << message;
  EXPECT_EQ(contentOf(dir + "/b.txt"), "old b");
  EXPECT_EQ(typeOf(fifo), mode_t(S_IFIFO));
  EXPECT_EQ(namesIn(dir).size(), 2u) << "a temporary was left";
}

TEST(OutputTargets, CharacterDevicesAreWrittenThroughNeverReplaced)
{
  const std::string dir = scratch("target-devices");
  writeText(dir + "/b.txt", "old b");
  {
    AtomicFileSet files;
    TemporaryFile& null = files.add("/dev/null");
    // Before any commit: a set that would rename over the system's device is never committed.
    ASSERT_TRUE(null.writesThrough());
    null.write("picture", 7);
    files.add(dir + "/b.txt").write("new b", 5);
    files.commit();
  }
  EXPECT_EQ(typeOf("/dev/null"), mode_t(S_IFCHR));
  EXPECT_EQ(contentOf(dir + "/b.txt"), "new b");
  EXPECT_TRUE(namesIn("/dev").size() > 0);
  for (const std::string& name : namesIn("/dev"))
    EXPECT_FALSE(isTemporaryName(name)) << "a temporary was made in /dev: " << name;

  // /dev/full refuses every byte: the error is the device's, and nothing else of the set changes.
  AtomicFileSet files;
  TemporaryFile& full = files.add("/dev/full");
  ASSERT_TRUE(full.writesThrough());
  full.write("picture", 7);
  files.add(dir + "/b.txt").write("newer b", 7);
  const std::string message = errorOf([&] { files.commit(); });
  EXPECT_NE(message.find("\"/dev/full\": " + std::string(std::strerror(ENOSPC))), std::string::npos)
    << message;
  EXPECT_EQ(typeOf("/dev/full"), mode_t(S_IFCHR));
  EXPECT_EQ(contentOf(dir + "/b.txt"), "new b");
  EXPECT_EQ(namesIn(dir).size(), 1u) << "a temporary was left";
}

TEST(OutputTargets, SocketsDirectoriesAndLinksToDevicesAreRefused)
{
  const std::string dir = scratch("target-refused");
  const std::string socketPath = dir + "/s.png";
  const int s = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(s, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(socketPath.size(), sizeof address.sun_path);
  std::strcpy(address.sun_path, socketPath.c_str());
  ASSERT_EQ(bind(s, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  close(s);
  ASSERT_EQ(symlink("/dev/null", (dir + "/null.png").c_str()), 0);
  ASSERT_TRUE(SystemTools::MakeDirectory(dir + "/d.png"));

  AtomicFileSet files;
  const std::string socketMessage = errorOf([&] { files.add(socketPath); });
  EXPECT_NE(socketMessage.find("it is a socket"), std::string::npos) << socketMessage;
  const std::string linkMessage = errorOf([&] { files.add(dir + "/null.png"); });
  EXPECT_NE(linkMessage.find("symbolic link to a character device"), std::string::npos)
    << linkMessage;
  const std::string dirMessage = errorOf([&] { files.add(dir + "/d.png"); });
  EXPECT_NE(dirMessage.find(std::strerror(EISDIR)), std::string::npos) << dirMessage;
  EXPECT_EQ(typeOf(socketPath), mode_t(S_IFSOCK));
  EXPECT_EQ(typeOf(dir + "/null.png"), mode_t(S_IFLNK));
  EXPECT_EQ(namesIn(dir).size(), 3u) << "a temporary was left";
}

TEST(OutputTargets, FilesToRemoveGoWithTheCommitOrNotAtAll)
{
  const std::string dir = scratch("target-remove");
  for (const char* name : { "a", "old-1", "old-2", "keep" })
    writeText(dir + "/" + name, name);
  {
    AtomicFileSet files;
    files.add(dir + "/a").write("new a", 5);
    files.remove(dir + "/old-1");
    // Not committed: an error or an interrupt before the last step.
  }
  EXPECT_EQ(contentOf(dir + "/old-1"), "old-1");
  {
    AtomicFileSet files;
    files.add(dir + "/a").write("new a", 5);
    files.add(dir + "/c").write("new c", 5);
    files.remove(dir + "/old-1");
    files.remove(dir + "/old-2");
    EXPECT_THROW(files.add(dir + "/old-2"), std::runtime_error) << "written and removed";
    // c's rename fails after a's: everything comes back, the files to remove too.
    ASSERT_TRUE(SystemTools::MakeDirectory(dir + "/c/inside"));
    EXPECT_THROW(files.commit(), std::runtime_error);
  }
  EXPECT_EQ(contentOf(dir + "/a"), "a");
  EXPECT_EQ(contentOf(dir + "/old-1"), "old-1");
  EXPECT_EQ(contentOf(dir + "/old-2"), "old-2");
  EXPECT_EQ(namesIn(dir).size(), 5u) << "a temporary or a file moved aside was left";
  SystemTools::RemoveADirectory(dir + "/c");

  AtomicFileSet files;
  files.add(dir + "/a").write("new a", 5);
  files.remove(dir + "/old-1");
  files.remove(dir + "/old-2");
  files.remove(dir + "/never-there");
  files.commit();
  EXPECT_EQ(contentOf(dir + "/a"), "new a");
  EXPECT_EQ(contentOf(dir + "/keep"), "keep");
  EXPECT_EQ(typeOf(dir + "/old-1"), mode_t(0));
  EXPECT_EQ(typeOf(dir + "/old-2"), mode_t(0));
  EXPECT_EQ(namesIn(dir).size(), 2u) << "a temporary or a file moved aside was left";
}

TEST(OutputTargets, ASetOfManyFilesInOneFolderHoldsOneDescriptorOfIt)
{
  const std::string dir = scratch("target-many");
  const std::size_t before = openDescriptors();
  AtomicFileSet files;
  for (int k = 0; k < 300; ++k)
  {
    TemporaryFile& file = files.add(dir + "/f-" + std::to_string(k));
    file.write("x", 1);
    file.finish();
  }
  EXPECT_LE(openDescriptors(), before + 1);
  files.commit();
  EXPECT_EQ(namesIn(dir).size(), 300u);
}

TEST(OutputTargets, AMovieInALargerSetAppearsWithTheSet)
{
  const std::string dir = scratch("target-movie");
  vtkNew<vtkImageData> frame;
  frame->SetDimensions(16, 16, 1);
  vtkNew<vtkUnsignedCharArray> colors;
  colors->SetName("Colors");
  colors->SetNumberOfComponents(3);
  colors->SetNumberOfTuples(16 * 16);
  colors->Fill(128);
  frame->GetPointData()->AddArray(colors);
  for (bool commit : { false, true })
  {
    AtomicFileSet files;
    MovieWriter movie(dir + "/m.ogv", 10, &files);
    movie.addFrame(frame);
    movie.addFrame(frame);
    files.add(dir + "/m.pvd").write("series", 6);
    movie.close();
    EXPECT_EQ(typeOf(dir + "/m.ogv"), mode_t(0)) << "the movie appeared before the set";
    if (commit)
      files.commit();
  }
  EXPECT_EQ(typeOf(dir + "/m.ogv"), mode_t(S_IFREG));
  EXPECT_EQ(contentOf(dir + "/m.ogv").rfind("OggS", 0), 0u);
  EXPECT_EQ(namesIn(dir).size(), 2u) << "a temporary was left";
}
