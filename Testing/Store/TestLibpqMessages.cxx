// libpq's messages as the store passes them on: one line each (pg::oneLine). First messages that
// libpq 15 and PostgreSQL 15 printed for real failures, kept verbatim with what the line must be;
// then the same kinds of failure brought about for real (a socket that does not exist, a server
// error with a DETAIL or a HINT, a server stopped under an open session), through the store's own
// paths, so that every place a message is built is seen to join it.
#include "PgSession.h"
#include "RayStore.h"
#include "SharedServer.h"
#include "StoreTestSupport.h"
#include "ThrowawayPostgres.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>

using asrt::RayStore;
using asrt::StoreError;
using asrt::testing::ThrowawayPostgres;
using namespace asrt::testing;

namespace
{
struct Captured
{
  const char* what;
  const char* message;  ///< as libpq gave it
  const char* expected; ///< the one line
};

const Captured Messages[] = {
  { "a socket that does not exist",
    "connection to server on socket \"/nonexistent/.s.PGSQL.1\" failed: No such file or "
    "directory\n\tIs the server running locally and accepting connections on that socket?\n",
    "connection to server on socket \"/nonexistent/.s.PGSQL.1\" failed: No such file or "
    "directory; is the server running locally and accepting connections on that socket?" },
  { "a refused TCP connection",
    "connection to server at \"127.0.0.1\", port 1 failed: Connection refused\n\tIs the server "
    "running on that host and accepting TCP/IP connections?\n",
    "connection to server at \"127.0.0.1\", port 1 failed: Connection refused; is the server "
    "running on that host and accepting TCP/IP connections?" },
  { "an error with a DETAIL",
    "ERROR:  duplicate key value violates unique constraint \"t_pkey\"\nDETAIL:  Key (id)=(1) "
    "already exists.\n",
    "ERROR:  duplicate key value violates unique constraint \"t_pkey\"; DETAIL:  Key (id)=(1) "
    "already exists." },
  { "an error with the statement's excerpt",
    "ERROR:  relation \"nosuch\" does not exist\nLINE 1: SELECT * FROM nosuch\n"
    "                      ^\n",
    "ERROR:  relation \"nosuch\" does not exist" },
  { "an excerpt, then a HINT",
    "ERROR:  function pg_read_file(integer) does not exist\nLINE 1: SELECT pg_read_file(1)\n"
    "               ^\nHINT:  No function matches the given name and argument types. You might "
    "need to add explicit type casts.\n",
    "ERROR:  function pg_read_file(integer) does not exist; HINT:  No function matches the given "
    "name and argument types. You might need to add explicit type casts." },
  { "a DETAIL of two lines, a HINT and a CONTEXT",
    "ERROR:  boom\nDETAIL:  two\nlines\nHINT:  hint here\nCONTEXT:  PL/pgSQL function "
    "inline_code_block line 1 at RAISE\n",
    "ERROR:  boom; DETAIL:  two; lines; HINT:  hint here" },
  { "a terminated backend",
    "FATAL:  terminating connection due to administrator command\nserver closed the connection "
    "unexpectedly\n\tThis probably means the server terminated abnormally\n\tbefore or while "
    "processing the request.\n",
    "FATAL:  terminating connection due to administrator command; server closed the connection "
    "unexpectedly; this probably means the server terminated abnormally before or while "
    "processing the request." },
  { "a one-line message", "no connection to the server\n", "no connection to the server" },
  { "the same said twice (a failed send, then the failed read)",
    "server closed the connection unexpectedly\n\tThis probably means the server terminated "
    "abnormally\n\tbefore or while processing the request.\nserver closed the connection "
    "unexpectedly\n\tThis probably means the server terminated abnormally\n\tbefore or while "
    "processing the request.\n",
    "server closed the connection unexpectedly; this probably means the server terminated "
    "abnormally before or while processing the request." },
};

/// The socket that `conninfo` ("host=DIR port=N ...") names, as libpq spells it.
std::string socketOf(const std::string& conninfo)
{
  std::istringstream fields(conninfo);
  std::string field, host, port;
  while (fields >> field)
  {
    if (field.rfind("host=", 0) == 0)
      host = field.substr(5);
    if (field.rfind("port=", 0) == 0)
      port = field.substr(5);
  }
  return host + "/.s.PGSQL." + port;
}

struct PlainConnection
{
  explicit PlainConnection(const std::string& conninfo)
    : Conn(PQconnectdb(conninfo.c_str()))
  {
    // The server's goodbye ("terminating connection due to ...") is a notice: not for stderr.
    PQsetNoticeProcessor(
      this->Conn, [](void*, const char*) {}, nullptr);
  }
  ~PlainConnection() { PQfinish(this->Conn); }
  PGconn* Conn;
};
}

TEST(LibpqMessages, CapturedMessagesBecomeOneLine)
{
  for (const Captured& c : Messages)
    EXPECT_EQ(asrt::pg::oneLine(c.message), c.expected) << c.what;
}

TEST(LibpqMessages, AFailedConnectionIsOneLine)
{
  PlainConnection plain("host=/nonexistent-asrt-dir port=1");
  const std::string raw = PQerrorMessage(plain.Conn);
  const std::string expected = "connection to server on socket "
                               "\"/nonexistent-asrt-dir/.s.PGSQL.1\" failed: No such file or "
                               "directory; is the server running locally and accepting "
                               "connections on that socket?";
  ASSERT_NE(raw.find("\n\t"), std::string::npos) << "libpq's message has no second line: " << raw;
  EXPECT_EQ(asrt::pg::oneLine(raw), expected);
  // The store's own message.
  EXPECT_EQ(errorOf([] { RayStore store("host=/nonexistent-asrt-dir port=1"); }),
            "cannot connect to PostgreSQL: " + expected);
}

TEST(LibpqMessages, ServerErrorsKeepTheirDetailAndHintOnOneLine)
{
  const std::string conninfo = databaseNamed("lm_" + currentTestName());
  asrt::pg::Connection conn = asrt::pg::connect(conninfo);
  asrt::pg::exec(conn.get(), "DROP TABLE IF EXISTS t", "dropping failed");
  asrt::pg::exec(conn.get(), "CREATE TABLE t (id integer PRIMARY KEY)", "creating failed");
  asrt::pg::exec(conn.get(), "INSERT INTO t VALUES (1)", "inserting failed");
  try
  {
    asrt::pg::exec(conn.get(), "INSERT INTO t VALUES (1)", "inserting again failed");
    FAIL() << "a duplicate key was inserted";
  }
  catch (const StoreError& e)
  {
    EXPECT_EQ(std::string(e.what()),
              "inserting again failed: ERROR:  duplicate key value violates unique constraint "
              "\"t_pkey\"; DETAIL:  Key (id)=(1) already exists.");
    EXPECT_EQ(e.sqlState(), "23505");
  }
  const std::string hint = "ERROR:  function pg_read_file(integer) does not exist; HINT:  No "
                           "function matches the given name and argument types. You might need "
                           "to add explicit type casts.";
  EXPECT_EQ(errorOf([&] { asrt::pg::exec(conn.get(), "SELECT pg_read_file(1)", "reading"); }),
            "reading: " + hint);
  // A query whose rows are streamed builds its message apart.
  EXPECT_EQ(errorOf(
              [&]
              {
                asrt::pg::Params().stream(conn.get(), "SELECT pg_read_file(1)", "streaming",
                                          [](const PGresult*) {});
              }),
            "streaming: " + hint);
}

TEST(LibpqMessages, AServerStoppedUnderASessionIsOneLine)
{
  ThrowawayPostgres server;
  RayStore store(server.conninfo());
  store.migrate();
  store.listFrames(); // the schema checked: the next call's first statement is its own
  PlainConnection plain(server.conninfo());
  ASSERT_EQ(PQstatus(plain.Conn), CONNECTION_OK) << PQerrorMessage(plain.Conn);
  server.stop();

  PQclear(PQexec(plain.Conn, "SELECT 1"));
  const std::string raw = PQerrorMessage(plain.Conn);
  const std::string closed = "server closed the connection unexpectedly; this probably means "
                             "the server terminated abnormally before or while processing the "
                             "request.";
  ASSERT_NE(raw.find("\n\t"), std::string::npos) << "libpq's message has no second line: " << raw;
  EXPECT_EQ(asrt::pg::oneLine(raw), closed);

  // The store's messages: the statement that met the closed connection (the read's first, which
  // sets its lock timeout; libpq may take a second statement to see the connection as lost), then
  // the reconnection that found no server.
  const std::string lost = "reading from the store failed: " + closed;
  EXPECT_EQ(errorOf([&] { store.listFrames(); }), lost);
  const std::string noServer = "lost the connection to PostgreSQL and could not reconnect: "
                               "connection to server on socket \"" +
                               socketOf(server.conninfo()) +
                               "\" failed: No such file or directory; is the server running "
                               "locally and accepting connections on that socket?";
  std::string error;
  for (int attempt = 0; attempt < 3 && error != noServer; ++attempt)
  {
    error = errorOf([&] { store.listFrames(); });
    if (error != noServer)
    {
      EXPECT_EQ(error, lost);
    }
  }
  EXPECT_EQ(error, noServer);
}
