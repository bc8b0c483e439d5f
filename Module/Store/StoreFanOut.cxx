#include "StoreFanOut.h"

#include <exception>
#include <thread>

namespace asrt
{
namespace storage
{
std::vector<PGconn*> HelperConnections::get(int wanted)
{
  std::vector<PGconn*> out;
  for (std::size_t k = 0; int(out.size()) < wanted; ++k)
  {
    if (k == this->Conns.size())
    {
      try
      {
        this->Conns.push_back(pg::connect(this->Conninfo));
      }
      catch (const StoreError&)
      {
        break;
      }
    }
    PGconn* c = this->Conns[k].get();
    if (PQstatus(c) != CONNECTION_OK && !pg::reconnect(c))
    {
      break;
    }
    out.push_back(c);
  }
  return out;
}

void FanOut::run(const std::function<void(PGconn*, std::size_t)>& helperShare,
                 const std::function<void()>& ownShare)
{
  std::vector<std::exception_ptr> errors(this->Helpers.size());
  std::vector<std::thread> threads;
  auto joinAll = [&threads]
  {
    for (std::thread& t : threads)
    {
      t.join();
    }
  };
  auto share = [this, &errors, &helperShare](std::size_t k)
  {
    PGconn* conn = this->Helpers[k];
    try
    {
      helperShare(conn, k);
    }
    catch (...)
    {
      pg::rollback(conn);
      errors[k] = std::current_exception();
      this->Failed = true;
    }
  };
  try
  {
    for (std::size_t k = 0; k < this->Helpers.size(); ++k)
    {
      threads.emplace_back(share, k);
    }
  }
  catch (...)
  {
    // A thread could not start (std::system_error): the others stop as after a failure.
    this->Failed = true;
    joinAll();
    throw;
  }
  std::exception_ptr ownError;
  try
  {
    ownShare();
  }
  catch (...)
  {
    ownError = std::current_exception();
    this->Failed = true;
  }
  joinAll();
  auto stopped = [](const std::exception_ptr& e)
  {
    try
    {
      std::rethrow_exception(e);
    }
    catch (const ShareStopped&)
    {
      return true;
    }
    catch (...)
    {
      return false;
    }
  };
  std::vector<std::exception_ptr> all{ ownError };
  all.insert(all.end(), errors.begin(), errors.end());
  for (const std::exception_ptr& e : all)
  {
    if (e && !stopped(e))
    {
      std::rethrow_exception(e);
    }
  }
  for (const std::exception_ptr& e : all)
  {
    if (e)
    {
      std::rethrow_exception(e);
    }
  }
}
}
}
