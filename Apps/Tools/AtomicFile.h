// Files that appear whole or not at all, and sets of files that appear together. Each file is
// first written to a temporary of its own in the target's directory, created new (O_CREAT|O_EXCL|
// O_NOFOLLOW, under an unpredictable name), so that nothing planted in the folder (a symbolic
// link at a name the program would use) is ever written through; the temporaries are renamed into
// place in one final step (rename(2) replaces a link at the final name, it never follows it). An
// error or an interrupt before that step leaves the previous files as they were and no temporary.
//
// Renaming is for regular files and missing names only. A character device (/dev/null, a
// terminal) or a FIFO that the caller names is written through instead, never replaced: it is
// opened at once (O_WRONLY|O_NONBLOCK, without O_CREAT or O_TRUNC, so a FIFO nobody reads is
// refused instead of waited for), the file's bytes are kept in memory, and they are written
// through it in the final step, before the renames. Anything else (a block device, a socket, a
// directory, a symbolic link to a device) is refused when the file is added.
#ifndef asrt_tools_AtomicFile_h
#define asrt_tools_AtomicFile_h

#include <sys/stat.h>
#include <sys/types.h>

#include <functional>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
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

/// Thrown when Ctrl-C or SIGTERM (interruptRequested) stops a write through a FIFO or device
/// that blocks.
struct WriteInterrupted : std::runtime_error
{
  WriteInterrupted()
    : std::runtime_error("interrupted while writing")
  {
  }
};

/// A new, empty file next to `path`, to be renamed to `path` by an AtomicFileSet. Destroyed
/// before that, it removes itself. When `path` is a character device or a FIFO, the file is
/// written through it instead (see above): the new file is then an anonymous one in memory.
class TemporaryFile
{
public:
  /// Creates the file (mode 0644 less the umask). Throws std::runtime_error naming `path` with the
  /// system's reason (no such directory, permission denied, `path` is a directory, a socket, a
  /// FIFO no process reads, ...).
  explicit TemporaryFile(const std::string& path);
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

  /// The final name.
  const std::string& path() const { return this->Path; }
  /// The temporary's own name (in the same directory); empty for a file written through.
  std::string temporaryPath() const;
  /// Whether `path` is a character device or a FIFO that the file is written through.
  bool writesThrough() const { return this->Target >= 0; }
  /// A name that opens the very file created ("/proc/self/fd/N"), whatever has become of its
  /// directory entry: for writers that open files by name (VTK's).
  std::string openName() const;
  /// The open descriptor, readable and writable (-1 once finish() closed it).
  int descriptor() const { return this->Fd; }
  /// Appends `size` bytes; throws std::runtime_error with the system's reason (EFBIG, ENOSPC).
  void write(const char* data, std::size_t size);
  /// Makes the data durable and closes the file; throws std::runtime_error naming path() with the
  /// system's reason if it reports an error (a full disk may only show here).
  void finish();

private:
  friend class AtomicFileSet;
  struct Directory;
  /// `folder` gives the open directory of `path`'s folder; asked only for a file to rename.
  TemporaryFile(const std::string& path, const std::function<std::shared_ptr<Directory>()>& folder);
  /// For a character device or FIFO at `path`: opens it, and an anonymous file for the bytes.
  void openThrough(const struct ::stat& named);
  /// Writes the finished bytes through the device or FIFO.
  void writeThroughTarget();
  std::shared_ptr<Directory> Dir; ///< null for a file written through
  std::string Path;
  std::string Name;      ///< the final name within Dir
  std::string Temporary; ///< the temporary's name within Dir
  int Fd = -1;
  int Target = -1; ///< the device or FIFO written through, else -1
  int Staged = -1; ///< a finished file's bytes, until they are written through Target
  dev_t Device = 0;
  ino_t Inode = 0;
  bool Placed = false;
};

/// Files that appear together: add() creates each one's temporary, commit() renames them all
/// into place. If one cannot be put in place, those already renamed are undone (the files they
/// replaced come back) and the error propagates; without commit(), the destructor removes every
/// temporary. Either the whole new set is there, or none of it and the previous files untouched.
/// Members written through a device or FIFO are written first in commit(): bytes that went
/// through cannot be taken back, so a failure there leaves the files to be renamed untouched, and
/// a failure after it leaves only those bytes sent.
class AtomicFileSet
{
public:
  AtomicFileSet() = default;
  ~AtomicFileSet();
  AtomicFileSet(const AtomicFileSet&) = delete;
  AtomicFileSet& operator=(const AtomicFileSet&) = delete;

  /// A new member; throws std::runtime_error if its temporary cannot be created or `path` is
  /// already in the set. Members in one directory share its descriptor.
  TemporaryFile& add(const std::string& path);
  /// A file the set removes: it disappears in commit(), with the new members, and comes back if
  /// the commit fails. Nothing happens if it is gone by then. Throws std::runtime_error if its
  /// directory cannot be opened or `path` is a member.
  void remove(const std::string& path);
  /// Every member finished (TemporaryFile::finish, for those not finished yet), then written
  /// through or renamed, and the files to remove removed. Throws WriteInterrupted if an interrupt
  /// stops a write through a FIFO or device (nothing is renamed then).
  void commit();
  std::vector<std::string> paths() const;
  std::size_t size() const { return this->Files.size(); }

private:
  struct Removal
  {
    std::shared_ptr<TemporaryFile::Directory> Dir;
    std::string Path, Name;
    std::string Aside; ///< the hidden name it was moved to in commit(), until it is deleted
  };
  /// The open directory of `path`'s folder: one a member has open, or opened anew.
  std::shared_ptr<TemporaryFile::Directory> directoryFor(const std::string& path);
  /// Throws if `path` is a member or a file to remove already.
  void checkNew(const std::string& path) const;
  /// Every member finished, and still the file its temporary name was created for.
  void check();
  /// Renames the members written to temporaries into place; on a failure puts back what the
  /// renames replaced and throws.
  void rename();
  /// Moves the files to remove aside; on a failure puts them back and throws.
  void moveAside();
  /// Puts back what the renames of the first `placed` members replaced.
  void undo(std::size_t placed, const std::vector<std::string>& backups) noexcept;
  /// Puts back the files moved aside.
  void restoreRemoved() noexcept;
  /// Removes the temporaries not in place.
  void discard() noexcept;
  std::vector<std::unique_ptr<TemporaryFile>> Files;
  std::vector<Removal> Removals;
  std::vector<std::string> Backups; ///< during commit(): each member's previous file, kept
  std::set<std::string> Named;      ///< the paths of the members and of the files to remove
  /// Each folder's directory, opened once: a sequence of thousands of files in one folder holds
  /// one descriptor of it.
  std::map<std::string, std::shared_ptr<TemporaryFile::Directory>> Folders;
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
