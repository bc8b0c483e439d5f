// Files that appear whole or not at all: written under a temporary name in the same directory and
// renamed into place (rename(2) is atomic within a file system), so that an error or an interrupt
// never leaves a half-written image, dataset or movie behind.
#ifndef asrt_tools_AtomicFile_h
#define asrt_tools_AtomicFile_h

#include <functional>
#include <string>

namespace asrt
{
namespace tools
{
/// A temporary name next to `path` (hidden, unique to this process).
std::string temporaryNameFor(const std::string& path);

/// Calls `write(temporaryPath)`, then renames the temporary file to `path`. If `write` throws or
/// leaves no file, the temporary file is removed and the error propagates (std::runtime_error
/// naming `path` when nothing was written).
void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write);

/// Writes `content` to `path` atomically; throws std::runtime_error with the system's reason.
void writeFileAtomically(const std::string& path, const std::string& content);
}
}

#endif
