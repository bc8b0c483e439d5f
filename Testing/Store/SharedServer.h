// One throwaway server for a whole GoogleTest program, started on first use and stopped when the
// program's tests end (ctest runs each test in a process of its own, so a test pays for one server
// start), and a database of its own for each test, so that tests do not see each other's frames.
#ifndef asrt_SharedServer_h
#define asrt_SharedServer_h

#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>

#include <cctype>
#include <memory>
#include <string>

namespace asrt
{
namespace testing
{
inline std::unique_ptr<ThrowawayPostgres>& sharedServerSlot()
{
  static std::unique_ptr<ThrowawayPostgres> server;
  return server;
}

inline ThrowawayPostgres& sharedServer()
{
  auto& s = sharedServerSlot();
  if (!s)
    s = std::make_unique<ThrowawayPostgres>();
  return *s;
}

class StopSharedServer : public ::testing::Environment
{
public:
  void TearDown() override { sharedServerSlot().reset(); }
};
inline const ::testing::Environment* const kStopSharedServer =
  ::testing::AddGlobalTestEnvironment(new StopSharedServer);

/// Conninfo of the shared server's database `name`, lower-cased and cut to PostgreSQL's 63-byte
/// identifiers (created if missing).
inline std::string databaseNamed(std::string name)
{
  for (char& c : name)
    c = char(std::tolower(static_cast<unsigned char>(c)));
  return sharedServer().conninfo(name.substr(0, 63));
}

/// The running test's name, and its suite's.
inline std::string currentTestName()
{
  return ::testing::UnitTest::GetInstance()->current_test_info()->name();
}
inline std::string currentTestSuiteName()
{
  return ::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name();
}
}
}

#endif
