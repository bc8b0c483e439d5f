#include "AtomicFile.h"

#include "InterruptibleRead.h"

#include <dirent.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <set>
#include <stdexcept>
#include <utility>

namespace asrt
{
namespace tools
{
namespace
{
constexpr const char* kSuffix = ".part";
constexpr std::size_t kRandomChars = 6;
/// Names longer than this are shortened in their temporary's name, which must stay within
/// NAME_MAX (255) with the PID and the random part.
constexpr std::size_t kNameCharsKept = 200;

std::runtime_error failure(const std::string& path, int error)
{
  return std::runtime_error("cannot write \"" + path + "\": " + std::strerror(error));
}

std::runtime_error refusal(const std::string& path, const std::string& why)
{
  return std::runtime_error("cannot write \"" + path + "\": " + why);
}

/// What a file of this type is, for a refusal.
const char* kindOf(mode_t mode)
{
  return S_ISCHR(mode)    ? "a character device"
         : S_ISFIFO(mode) ? "a FIFO"
         : S_ISBLK(mode)  ? "a block device"
         : S_ISSOCK(mode) ? "a socket"
         : S_ISDIR(mode)  ? "a directory"
                          : "not a regular file";
}

/// Refuses what is at `path` (not followed), unless it is missing, a regular file or a link to
/// one (replaced by the rename), or a character device or FIFO (written through).
void refuseNonRegular(const std::string& path, const struct stat& named)
{
  if (S_ISDIR(named.st_mode))
    throw failure(path, EISDIR);
  if (S_ISBLK(named.st_mode) || S_ISSOCK(named.st_mode))
    throw refusal(path, std::string("it is ") + kindOf(named.st_mode) +
                          " (asrt writes regular files, and through character devices and FIFOs)");
  struct stat target;
  // A link is replaced, never followed: one to a device or FIFO (planted, or /dev/stdout) would
  // replace a name the user surely meant to write through.
  if (S_ISLNK(named.st_mode) && stat(path.c_str(), &target) == 0 && !S_ISREG(target.st_mode) &&
      !S_ISDIR(target.st_mode))
    throw refusal(path, std::string("it is a symbolic link to ") + kindOf(target.st_mode) +
                          " (name the device or FIFO itself)");
}

/// Writes all of `data` to a FIFO or device opened non-blocking, waiting for it between writes
/// in a way an interrupt always ends (WriteInterrupted); a reader gone is an error (EPIPE).
void writeAll(int fd, const char* data, std::size_t size, const std::string& path)
{
  while (size > 0)
  {
    if (!waitForDescriptor(fd, POLLOUT))
      throw WriteInterrupted();
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && (errno == EINTR || errno == EAGAIN))
      continue;
    if (n <= 0)
      throw failure(path, n < 0 ? errno : EIO);
    data += n;
    size -= std::size_t(n);
  }
}

/// Blocks SIGPIPE while it lives, and consumes one that arrived meanwhile.
class PipeSignalBlocked
{
public:
  PipeSignalBlocked()
  {
    sigemptyset(&this->Pipe);
    sigaddset(&this->Pipe, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &this->Pipe, &this->Old);
  }
  ~PipeSignalBlocked()
  {
    const timespec zero = { 0, 0 };
    sigset_t pending;
    if (sigpending(&pending) == 0 && sigismember(&pending, SIGPIPE) == 1)
      sigtimedwait(&this->Pipe, nullptr, &zero);
    pthread_sigmask(SIG_SETMASK, &this->Old, nullptr);
  }
  PipeSignalBlocked(const PipeSignalBlocked&) = delete;
  PipeSignalBlocked& operator=(const PipeSignalBlocked&) = delete;

private:
  sigset_t Pipe, Old;
};

std::string randomChars()
{
  static const char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  unsigned char bytes[kRandomChars];
  std::size_t got = 0;
  while (got < sizeof bytes)
  {
    const ssize_t n = getrandom(bytes + got, sizeof bytes - got, 0);
    if (n < 0 && errno != EINTR)
      throw std::runtime_error(std::string("getrandom: ") + std::strerror(errno));
    got += n > 0 ? std::size_t(n) : 0;
  }
  std::string out;
  for (unsigned char b : bytes)
    out += alphabet[b % (sizeof alphabet - 1)];
  return out;
}

/// A fresh temporary name for `name`, in the form isTemporaryName() recognises.
std::string temporaryNameFor(const std::string& name)
{
  return "." + name.substr(0, kNameCharsKept) + "." + std::to_string(getpid()) + "." +
         randomChars() + kSuffix;
}

bool allDigits(const std::string& s)
{
  return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
}

int removeStaleTemporariesIn(int dirFd)
{
  const int listFd = dup(dirFd);
  DIR* listing = listFd >= 0 ? fdopendir(listFd) : nullptr;
  if (!listing)
  {
    if (listFd >= 0)
      close(listFd);
    return 0;
  }
  rewinddir(listing);
  int removed = 0;
  while (const dirent* entry = readdir(listing))
  {
    pid_t writer = 0;
    struct stat st;
    if (!isTemporaryName(entry->d_name, &writer) || writer == getpid())
      continue;
    // kill(pid, 0) fails with ESRCH only for a process that does not exist; EPERM means alive.
    if (kill(writer, 0) == 0 || errno != ESRCH)
      continue;
    if (fstatat(dirFd, entry->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode) ||
        st.st_uid != geteuid())
      continue;
    if (unlinkat(dirFd, entry->d_name, 0) == 0)
      ++removed;
  }
  closedir(listing);
  return removed;
}
}

bool isTemporaryName(const std::string& fileName, pid_t* writer)
{
  const std::size_t suffix = std::strlen(kSuffix);
  if (fileName.size() < 1 + 1 + 1 + 1 + 1 + kRandomChars + suffix || fileName[0] != '.' ||
      fileName.compare(fileName.size() - suffix, suffix, kSuffix) != 0)
    return false;
  const std::string stem = fileName.substr(0, fileName.size() - suffix);
  const std::size_t randomDot = stem.size() - kRandomChars - 1;
  if (stem[randomDot] != '.')
    return false;
  for (std::size_t k = randomDot + 1; k < stem.size(); ++k)
    if (!std::isalnum(static_cast<unsigned char>(stem[k])))
      return false;
  const std::size_t pidDot = stem.rfind('.', randomDot - 1);
  if (pidDot == std::string::npos || pidDot < 2)
    return false;
  const std::string pid = stem.substr(pidDot + 1, randomDot - pidDot - 1);
  if (!allDigits(pid) || pid.size() > 9)
    return false;
  if (writer)
    *writer = static_cast<pid_t>(std::stol(pid));
  return true;
}

/// The target's directory, opened once: every name is then resolved in it (*at calls), so the
/// temporary and the final file are in the same directory even if its path changes meanwhile.
struct TemporaryFile::Directory
{
  int Fd = -1;
  ~Directory()
  {
    if (this->Fd >= 0)
      close(this->Fd);
  }

  static std::shared_ptr<Directory> open(const std::string& dir, const std::string& forPath)
  {
    auto d = std::make_shared<Directory>();
    d->Fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (d->Fd < 0)
      throw failure(forPath, errno);
    cleanOnce(d->Fd);
    return d;
  }

  /// A second name for the file `name` (a hard link, not following a symbolic link), so that a
  /// failed commit can put it back; "" if there is no such file or no link can be made.
  std::string keep(const std::string& name) const
  {
    for (int attempt = 0; attempt < 100; ++attempt)
    {
      const std::string backup = temporaryNameFor(name);
      if (linkat(this->Fd, name.c_str(), this->Fd, backup.c_str(), 0) == 0)
        return backup;
      if (errno != EEXIST)
        return std::string();
    }
    return std::string();
  }

private:
  static void cleanOnce(int fd)
  {
    static std::mutex mutex;
    static std::set<std::pair<dev_t, ino_t>> cleaned;
    struct stat st;
    if (fstat(fd, &st) != 0)
      return;
    std::lock_guard<std::mutex> lock(mutex);
    if (cleaned.insert({ st.st_dev, st.st_ino }).second)
      removeStaleTemporariesIn(fd);
  }
};

int removeStaleTemporaries(const std::string& directory)
{
  const int fd = open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0)
    return 0;
  const int removed = removeStaleTemporariesIn(fd);
  close(fd);
  return removed;
}

TemporaryFile::TemporaryFile(const std::string& path)
  : TemporaryFile(path,
                  [&path]
                  {
                    const std::string parent = std::filesystem::path(path).parent_path().string();
                    return Directory::open(parent, path);
                  })
{
}

TemporaryFile::TemporaryFile(const std::string& path,
                             const std::function<std::shared_ptr<Directory>()>& folder)
  : Path(path)
{
  const std::filesystem::path p(path);
  this->Name = p.filename().string();
  if (this->Name.empty() || this->Name == "." || this->Name == "..")
    throw std::runtime_error("cannot write \"" + path + "\": not a file name");
  struct stat st;
  if (lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
  {
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))
    {
      this->openThrough(st);
      return;
    }
    refuseNonRegular(path, st);
  }
  this->Dir = folder();
  // Again through the directory opened: the name may have become a directory meanwhile.
  if (fstatat(this->Dir->Fd, this->Name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0 &&
      S_ISDIR(st.st_mode))
    throw failure(path, EISDIR);
  for (int attempt = 0; attempt < 100; ++attempt)
  {
    const std::string candidate = temporaryNameFor(this->Name);
    // O_EXCL: a new file or nothing, never one that exists (a planted link included). Readable
    // too, as the staging memfd of a file written through is: a writer may read back its bytes.
    const int fd = openat(this->Dir->Fd, candidate.c_str(),
                          O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd >= 0)
    {
      this->Fd = fd;
      this->Temporary = candidate;
      if (fstat(fd, &st) == 0)
      {
        this->Device = st.st_dev;
        this->Inode = st.st_ino;
      }
      return;
    }
    if (errno != EEXIST)
      throw failure(path, errno);
  }
  throw std::runtime_error("cannot write \"" + path + "\": no free temporary name");
}

void TemporaryFile::openThrough(const struct ::stat& named)
{
  // O_NONBLOCK: opening a FIFO that no process reads fails (ENXIO) instead of waiting for one,
  // and writes never block (writeAll waits where an interrupt can end the wait); O_NOFOLLOW: a
  // link put at the name since lstat is not followed.
  const int fd =
    open(this->Path.c_str(), O_WRONLY | O_NONBLOCK | O_NOCTTY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0 && errno == ENXIO && S_ISFIFO(named.st_mode))
    throw refusal(this->Path, "it is a FIFO that no process is reading (start the reader first)");
  if (fd < 0)
    throw failure(this->Path, errno);
  struct stat opened;
  const bool same =
    fstat(fd, &opened) == 0 && opened.st_dev == named.st_dev && opened.st_ino == named.st_ino;
  const int staging = same ? memfd_create("asrt-output", MFD_CLOEXEC) : -1;
  const int error = errno;
  if (staging < 0)
  {
    close(fd);
    if (!same)
      throw refusal(this->Path, "it changed while it was being opened");
    throw failure(this->Path, error);
  }
  this->Target = fd;
  this->Fd = staging;
  this->Device = opened.st_dev;
  this->Inode = opened.st_ino;
}

void TemporaryFile::writeThroughTarget()
{
  PipeSignalBlocked blocked;
  std::vector<char> buffer(1 << 16);
  for (off_t offset = 0;;)
  {
    const ssize_t n = pread(this->Staged, buffer.data(), buffer.size(), offset);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      throw failure(this->Path, errno);
    if (n == 0)
      break;
    writeAll(this->Target, buffer.data(), std::size_t(n), this->Path);
    offset += n;
  }
  this->Placed = true;
}

TemporaryFile::~TemporaryFile()
{
  for (int fd : { this->Fd, this->Staged, this->Target })
    if (fd >= 0)
      close(fd);
  if (!this->Placed && !this->Temporary.empty())
    unlinkat(this->Dir->Fd, this->Temporary.c_str(), 0);
}

std::string TemporaryFile::temporaryPath() const
{
  if (this->Temporary.empty())
    return std::string();
  const std::string dir = std::filesystem::path(this->Path).parent_path().string();
  return (dir.empty() ? std::string() : dir + "/") + this->Temporary;
}

std::string TemporaryFile::openName() const
{
  if (this->Fd < 0)
    throw std::runtime_error("cannot write \"" + this->Path + "\": the file is already closed");
  const std::string name = "/proc/self/fd/" + std::to_string(this->Fd);
  if (access(name.c_str(), W_OK) != 0)
    throw std::runtime_error("cannot write \"" + this->Path + "\": " + name +
                             " is not there (is /proc mounted?)");
  return name;
}

void TemporaryFile::write(const char* data, std::size_t size)
{
  while (size > 0)
  {
    const ssize_t n = ::write(this->Fd, data, size);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      throw failure(this->Path, n < 0 ? errno : EIO);
    data += n;
    size -= std::size_t(n);
  }
}

void TemporaryFile::finish()
{
  if (this->Fd < 0)
    return;
  if (this->writesThrough())
  {
    // Kept, in memory, until the set's commit writes it through.
    this->Staged = this->Fd;
    this->Fd = -1;
    return;
  }
  // Data written by another descriptor (a VTK writer's) may only fail to reach the disk now.
  if (fsync(this->Fd) != 0)
    throw failure(this->Path, errno);
  const int fd = this->Fd;
  this->Fd = -1;
  if (close(fd) != 0)
    throw failure(this->Path, errno);
}

AtomicFileSet::~AtomicFileSet()
{
  // Files moved aside by a commit that did not finish: put back.
  this->restoreRemoved();
}

std::shared_ptr<TemporaryFile::Directory> AtomicFileSet::directoryFor(const std::string& path)
{
  const std::string parent = std::filesystem::path(path).parent_path().string();
  auto& folder = this->Folders[parent];
  if (!folder)
    folder = TemporaryFile::Directory::open(parent, path);
  return folder;
}

void AtomicFileSet::checkNew(const std::string& path) const
{
  if (this->Named.count(path))
    throw std::runtime_error("cannot write or remove \"" + path + "\" twice in one set of files");
}

TemporaryFile& AtomicFileSet::add(const std::string& path)
{
  this->checkNew(path);
  // A device or FIFO is written through: its folder is not opened.
  this->Files.push_back(std::unique_ptr<TemporaryFile>(
    new TemporaryFile(path, [this, &path] { return this->directoryFor(path); })));
  this->Named.insert(path);
  return *this->Files.back();
}

void AtomicFileSet::remove(const std::string& path)
{
  this->checkNew(path);
  Removal r;
  r.Dir = this->directoryFor(path);
  r.Path = path;
  r.Name = std::filesystem::path(path).filename().string();
  this->Removals.push_back(std::move(r));
  this->Named.insert(path);
}

std::vector<std::string> AtomicFileSet::paths() const
{
  std::vector<std::string> out;
  for (const auto& f : this->Files)
    out.push_back(f->Path);
  return out;
}

void AtomicFileSet::commit()
{
  try
  {
    this->check();
    // First what cannot be undone: should it fail, nothing else has changed.
    for (const auto& f : this->Files)
      if (f->writesThrough())
        f->writeThroughTarget();
    this->rename();
  }
  catch (...)
  {
    this->discard();
    throw;
  }
  try
  {
    this->moveAside();
  }
  catch (...)
  {
    this->undo(this->Files.size(), this->Backups);
    this->discard();
    throw;
  }
  std::set<const TemporaryFile::Directory*> folders;
  for (std::size_t k = 0; k < this->Files.size(); ++k)
    if (this->Files[k]->Dir)
    {
      if (!this->Backups[k].empty())
        unlinkat(this->Files[k]->Dir->Fd, this->Backups[k].c_str(), 0);
      folders.insert(this->Files[k]->Dir.get());
    }
  for (Removal& r : this->Removals)
  {
    if (!r.Aside.empty())
      unlinkat(r.Dir->Fd, r.Aside.c_str(), 0);
    r.Aside.clear();
    folders.insert(r.Dir.get());
  }
  // The renames themselves made durable, once per folder.
  for (const TemporaryFile::Directory* folder : folders)
    fsync(folder->Fd);
}

void AtomicFileSet::rename()
{
  this->Backups.assign(this->Files.size(), std::string());
  for (std::size_t k = 0; k < this->Files.size(); ++k)
    if (this->Files[k]->Dir)
      this->Backups[k] = this->Files[k]->Dir->keep(this->Files[k]->Name);
  for (std::size_t k = 0; k < this->Files.size(); ++k)
  {
    TemporaryFile& f = *this->Files[k];
    if (f.writesThrough())
      continue;
    if (renameat(f.Dir->Fd, f.Temporary.c_str(), f.Dir->Fd, f.Name.c_str()) != 0)
    {
      const int error = errno;
      this->undo(k, this->Backups);
      throw failure(f.Path, error);
    }
    f.Placed = true;
  }
}

void AtomicFileSet::moveAside()
{
  for (Removal& r : this->Removals)
  {
    for (int attempt = 0; attempt < 100 && r.Aside.empty(); ++attempt)
    {
      // Under a temporary's name: should the process die now, the next writer removes it.
      const std::string aside = temporaryNameFor(r.Name);
      if (renameat2(r.Dir->Fd, r.Name.c_str(), r.Dir->Fd, aside.c_str(), RENAME_NOREPLACE) == 0)
        r.Aside = aside;
      else if (errno == ENOENT)
        break; // gone already
      else if (errno != EEXIST)
      {
        const int error = errno;
        this->restoreRemoved();
        throw std::runtime_error("cannot remove \"" + r.Path + "\": " + std::strerror(error));
      }
    }
  }
}

void AtomicFileSet::restoreRemoved() noexcept
{
  for (Removal& r : this->Removals)
    if (!r.Aside.empty())
    {
      renameat(r.Dir->Fd, r.Aside.c_str(), r.Dir->Fd, r.Name.c_str());
      r.Aside.clear();
    }
}

void AtomicFileSet::check()
{
  for (const auto& f : this->Files)
    f->finish();
  for (const auto& f : this->Files)
  {
    if (f->writesThrough())
      continue;
    // The temporary's entry must still be the file created: someone with write access to the
    // folder could have put another file (or a link) under its name.
    struct stat st;
    if (fstatat(f->Dir->Fd, f->Temporary.c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0)
      throw failure(f->Path, errno);
    if (st.st_dev != f->Device || st.st_ino != f->Inode)
      throw std::runtime_error("cannot write \"" + f->Path +
                               "\": its temporary file was replaced by someone else");
  }
}

void AtomicFileSet::discard() noexcept
{
  for (const auto& f : this->Files)
    if (!f->Placed && !f->Temporary.empty())
    {
      unlinkat(f->Dir->Fd, f->Temporary.c_str(), 0);
      f->Temporary.clear();
    }
}

void AtomicFileSet::undo(std::size_t placed, const std::vector<std::string>& backups) noexcept
{
  for (std::size_t k = 0; k < this->Files.size(); ++k)
  {
    TemporaryFile& f = *this->Files[k];
    if (!f.Dir)
      continue;
    if (k < placed)
    {
      if (!backups[k].empty())
        renameat(f.Dir->Fd, backups[k].c_str(), f.Dir->Fd, f.Name.c_str());
      else
        unlinkat(f.Dir->Fd, f.Name.c_str(), 0);
      f.Placed = false;
      f.Temporary.clear();
    }
    else if (!backups[k].empty())
      unlinkat(f.Dir->Fd, backups[k].c_str(), 0);
  }
}

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
  AtomicFileSet files;
  TemporaryFile& file = files.add(path);
  write(file.openName());
  struct stat st;
  if (fstat(file.descriptor(), &st) != 0 || st.st_size == 0)
    throw std::runtime_error("cannot write \"" + path + "\"");
  files.commit();
}

void writeFileAtomically(const std::string& path, const std::string& content)
{
  AtomicFileSet files;
  files.add(path).write(content.data(), content.size());
  files.commit();
}
}
}
