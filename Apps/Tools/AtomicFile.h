// Files that appear whole or not at all, and sets of files that appear together. Each file is
// first written to a temporary of its own in the target's directory, created new (O_CREAT|O_EXCL|
// O_NOFOLLOW, under an unpredictable name), so that nothing planted in the folder (a symbolic
// link at a name the program would use) is ever written through; the temporaries are renamed into
// place in one final step (rename(2) replaces a link at the final name, it never follows it). An
// error or an interrupt before that step leaves the previous files as they were and no temporary.
#ifndef asrt_tools_AtomicFile_h
#define asrt_tools_AtomicFile_h

#include <sys/types.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace asrt
{
namespace tools
{
/// The temporaries' names: ".NAME.PID.XXXXXX.part" next to NAME (hidden; PID is the writing
/// process's, so that a dead writer's leftovers can be recognised; XXXXXX is random).
bool isTemporaryName(const std::string& fileName, pid_t* writer = nullptr);

/// Removes the temporaries that this program left in `directory` when it died: regular files of
/// this user named as isTemporaryName() says, whose process is gone (kill(pid, 0) says ESRCH).
/// Returns how many it removed. Creating a TemporaryFile does this once per directory.
int removeStaleTemporaries(const std::string& directory);

/// A new, empty file next to `path`, to be renamed to `path` by an AtomicFileSet. Destroyed
/// before that, it removes itself.
class TemporaryFile
{
public:
  /// Creates the file (mode 0644 less the umask). Throws std::runtime_error naming `path` with the
  /// system's reason (no such directory, permission denied, `path` is a directory, ...).
  explicit TemporaryFile(const std::string& path);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

  /// The final name.
  const std::string& path() const { return this->Path; }
  /// The temporary's own name (in the same directory).
  std::string temporaryPath() const;
  /// A name that opens the very file created ("/proc/self/fd/N"), whatever has become of its
  /// directory entry: for writers that open files by name (VTK's).
  std::string openName() const;
  /// The open descriptor (-1 once finish() closed it).
  int descriptor() const { return this->Fd; }
  /// Appends `size` bytes; throws std::runtime_error with the system's reason (EFBIG, ENOSPC).
  void write(const char* data, std::size_t size);
  /// Makes the data durable and closes the file; throws std::runtime_error naming path() with the
  /// system's reason if it reports an error (a full disk may only show here).
  void finish();

private:
  friend class AtomicFileSet;
  struct Directory;
  std::shared_ptr<Directory> Dir;
  std::string Path;
  std::string Name;      ///< the final name within Dir
  std::string Temporary; ///< the temporary's name within Dir
  int Fd = -1;
  dev_t Device = 0;
  ino_t Inode = 0;
  bool Placed = false;
};

/// Files that appear together: add() creates each one's temporary, commit() renames them all
/// into place. If one cannot be put in place, those already renamed are undone (the files they
/// replaced come back) and the error propagates; without commit(), the destructor removes every
/// temporary. Either the whole new set is there, or none of it and the previous files untouched.
class AtomicFileSet
{
public:
  AtomicFileSet() = default;
  ~AtomicFileSet();
  AtomicFileSet(const AtomicFileSet&) = delete;
  AtomicFileSet& operator=(const AtomicFileSet&) = delete;

  /// A new member; throws std::runtime_error if its temporary cannot be created or `path` is
  /// already in the set.
  TemporaryFile& add(const std::string& path);
  /// Every member finished (TemporaryFile::finish, for those not finished yet), then renamed.
  void commit();
  std::vector<std::string> paths() const;
  std::size_t size() const { return this->Files.size(); }

private:
  /// Every member finished, and still the file its temporary name was created for.
  void check();
  /// Puts back what the renames of the first `placed` members replaced.
  void undo(std::size_t placed, const std::vector<std::string>& backups) noexcept;
  /// Removes the temporaries not in place.
  void discard() noexcept;
  std::vector<std::unique_ptr<TemporaryFile>> Files;
};

/// Calls `write(name)` with a name to write the new file through (TemporaryFile::openName), then
/// puts it in place as `path`. If `write` throws or writes nothing, nothing changes and the error
/// propagates (std::runtime_error naming `path` when nothing was written).
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

/// Writes `content` to `path` atomically; throws std::runtime_error with the system's reason.
void writeFileAtomically(const std::string& path, const std::string& content);
}
}

#endif
