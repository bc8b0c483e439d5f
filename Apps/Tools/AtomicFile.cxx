#include "AtomicFile.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
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
  : Path(path)
{
  const std::filesystem::path p(path);
  this->Name = p.filename().string();
  if (this->Name.empty() || this->Name == "." || this->Name == "..")
    throw std::runtime_error("cannot write \"" + path + "\": not a file name");
  this->Dir = Directory::open(p.parent_path().string(), path);
  struct stat st;
  if (fstatat(this->Dir->Fd, this->Name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0 &&
      S_ISDIR(st.st_mode))
    throw failure(path, EISDIR);
  for (int attempt = 0; attempt < 100; ++attempt)
  {
    const std::string candidate = temporaryNameFor(this->Name);
    // O_EXCL: a new file or nothing, never one that exists (a planted link included).
    const int fd = openat(this->Dir->Fd, candidate.c_str(),
                          O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
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

TemporaryFile::~TemporaryFile()
{
  if (this->Fd >= 0)
    close(this->Fd);
  if (!this->Placed && !this->Temporary.empty())
    unlinkat(this->Dir->Fd, this->Temporary.c_str(), 0);
}

std::string TemporaryFile::temporaryPath() const
{
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
  // Data written by another descriptor (a VTK writer's) may only fail to reach the disk now.
  if (fsync(this->Fd) != 0)
    throw failure(this->Path, errno);
  const int fd = this->Fd;
  this->Fd = -1;
  if (close(fd) != 0)
    throw failure(this->Path, errno);
}

AtomicFileSet::~AtomicFileSet() = default;

TemporaryFile& AtomicFileSet::add(const std::string& path)
{
  for (const auto& f : this->Files)
    if (f->Path == path)
      throw std::runtime_error("cannot write \"" + path + "\" twice in one set of files");
  this->Files.push_back(std::make_unique<TemporaryFile>(path));
  return *this->Files.back();
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
  }
  catch (...)
  {
    this->discard();
    throw;
  }
  std::vector<std::string> backups;
  for (const auto& f : this->Files)
    backups.push_back(f->Dir->keep(f->Name));
  for (std::size_t k = 0; k < this->Files.size(); ++k)
  {
    TemporaryFile& f = *this->Files[k];
    if (renameat(f.Dir->Fd, f.Temporary.c_str(), f.Dir->Fd, f.Name.c_str()) != 0)
    {
      const int error = errno;
      this->undo(k, backups);
      this->discard();
      throw failure(f.Path, error);
    }
    f.Placed = true;
  }
  for (std::size_t k = 0; k < this->Files.size(); ++k)
    if (!backups[k].empty())
      unlinkat(this->Files[k]->Dir->Fd, backups[k].c_str(), 0);
  // The renames themselves made durable.
  for (const auto& f : this->Files)
    fsync(f->Dir->Fd);
}

void AtomicFileSet::check()
{
  for (const auto& f : this->Files)
    f->finish();
  for (const auto& f : this->Files)
  {
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
    if (k < placed)
    {
      if (!backups[k].empty())
        renameat(f.Dir->Fd, backups[k].c_str(), f.Dir->Fd, f.Name.c_str());
      else
        unlinkat(f.Dir->Fd, f.Name.c_str(), 0);
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
