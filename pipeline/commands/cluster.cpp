#include "pipeline/commands/cluster.h"

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <utility>

#ifdef GLINT_WITH_MPI
#include <mpi.h>
#endif

namespace glint {
namespace {

// Started by an MPI launcher: Open MPI's mpirun, or a PMI/PMIx launcher (MPICH, Slurm's srun).
bool launchedByMpi() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"}) {
    if (std::getenv(var) != nullptr) return true;
  }
  return false;
}

// Runs items one after another on one process.
void runAll(const std::vector<std::size_t>& items,
            const std::function<std::string(std::size_t)>& work,
            const std::function<void(std::size_t, const std::string&)>& done) {
  for (std::size_t item : items) {
    const std::string record = work(item);
    done(item, record);
  }
}

#ifdef GLINT_WITH_MPI
constexpr int kTagRequest = 1;  // worker → rank 0: the item it finished (or none) and its record
constexpr int kTagItem = 2;     // rank 0 → worker: the next item, or kNoItem
constexpr std::int64_t kNoItem = -1;

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

// A request: the finished item (kNoItem on the first) then its record's bytes.
std::string packRequest(std::int64_t item, const std::string& record) {
  std::string bytes(sizeof item, '\0');
  std::memcpy(bytes.data(), &item, sizeof item);
  return bytes + record;
}

void sendRequest(std::int64_t item, const std::string& record) {
  const std::string bytes = packRequest(item, record);
  check(MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_CHAR, 0, kTagRequest,
                 MPI_COMM_WORLD),
        "send");
}

// Rank 0: a thread computes rank 0's own items while this thread hands items to the others.
void serveAndWork(int size, const std::vector<std::size_t>& items,
                  const std::function<std::string(std::size_t)>& work,
                  const std::function<void(std::size_t, const std::string&)>& done) {
  std::mutex mutex;
  std::size_t next = 0;  // guarded by mutex
  std::deque<std::pair<std::size_t, std::string>> finished;
  bool local_done = false;
  std::exception_ptr local_error;
  auto take = [&]() -> std::int64_t {
    std::lock_guard lock(mutex);
    return next < items.size() ? static_cast<std::int64_t>(items[next++]) : kNoItem;
  };
  std::thread local([&] {
    try {
      for (std::int64_t item = take(); item != kNoItem; item = take()) {
        std::string record = work(static_cast<std::size_t>(item));
        std::lock_guard lock(mutex);
        finished.emplace_back(static_cast<std::size_t>(item), std::move(record));
      }
    } catch (...) {
      std::lock_guard lock(mutex);
      local_error = std::current_exception();
    }
    std::lock_guard lock(mutex);
    local_done = true;
  });

  int workers = size - 1;
  bool local_running = true;
  try {
    while (workers > 0 || local_running) {
      bool idle = true;
      int flag = 0;
      MPI_Status status;
      check(MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &flag, &status), "probe");
      if (flag != 0) {
        idle = false;
        int count = 0;
        check(MPI_Get_count(&status, MPI_CHAR, &count), "count");
        std::string bytes(static_cast<std::size_t>(count), '\0');
        check(MPI_Recv(bytes.data(), count, MPI_CHAR, status.MPI_SOURCE, kTagRequest,
                       MPI_COMM_WORLD, MPI_STATUS_IGNORE),
              "receive");
        std::int64_t item = kNoItem;
        if (bytes.size() < sizeof item) throw std::runtime_error("MPI: a short request");
        std::memcpy(&item, bytes.data(), sizeof item);
        if (item != kNoItem) done(static_cast<std::size_t>(item), bytes.substr(sizeof item));
        const std::int64_t reply = take();
        check(MPI_Send(&reply, 1, MPI_INT64_T, status.MPI_SOURCE, kTagItem, MPI_COMM_WORLD),
              "send");
        if (reply == kNoItem) --workers;
      }
      std::deque<std::pair<std::size_t, std::string>> mine;
      {
        std::lock_guard lock(mutex);
        mine.swap(finished);
        if (local_error) std::rethrow_exception(local_error);
        local_running = !local_done;
      }
      for (auto& [item, record] : mine) {
        idle = false;
        done(item, record);
      }
      // Polling, not a blocking receive: Open MPI's blocking calls spin a core, which the
      // local thread needs. A millisecond is nothing beside a scenario.
      if (idle) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  } catch (...) {
    // The caller aborts the job; the local thread must not outlive the data it uses.
    {
      std::lock_guard lock(mutex);
      next = items.size();
    }
    local.join();
    throw;
  }
  local.join();
  // Results the thread finished after the loop's last look.
  for (auto& [item, record] : finished) done(item, record);
}

// Ranks 1..N−1: ask for an item, compute it, send its record with the next request.
void workForRoot(const std::function<std::string(std::size_t)>& work) {
  sendRequest(kNoItem, "");
  while (true) {
    std::int64_t item = kNoItem;
    check(MPI_Recv(&item, 1, MPI_INT64_T, 0, kTagItem, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
          "receive");
    if (item == kNoItem) return;
    sendRequest(item, work(static_cast<std::size_t>(item)));
  }
}

// MPI counts are int: large arrays go in pieces.
template <class T>
void reduceToRoot(std::vector<T>& values, MPI_Datatype type, MPI_Op op, int rank) {
  constexpr std::size_t kPiece = std::size_t{1} << 26;
  for (std::size_t at = 0; at < values.size(); at += kPiece) {
    const int n = static_cast<int>(std::min(kPiece, values.size() - at));
    if (rank == 0) {
      check(MPI_Reduce(MPI_IN_PLACE, values.data() + at, n, type, op, 0, MPI_COMM_WORLD), "reduce");
    } else {
      check(MPI_Reduce(values.data() + at, nullptr, n, type, op, 0, MPI_COMM_WORLD), "reduce");
    }
  }
}
#endif

}  // namespace

bool Cluster::mpiBuilt() {
#ifdef GLINT_WITH_MPI
  return true;
#else
  return false;
#endif
}

Cluster::Cluster() {
#ifdef GLINT_WITH_MPI
  if (!launchedByMpi()) return;
  int provided = 0;
  // Only the main thread calls MPI; rank 0's computing thread does not.
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "init");
  mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#else
  (void)launchedByMpi;
#endif
}

Cluster::~Cluster() {
#ifdef GLINT_WITH_MPI
  if (mpi_) MPI_Finalize();
#endif
}

void Cluster::shareOut(const std::vector<std::size_t>& items,
                       const std::function<std::string(std::size_t)>& work,
                       const std::function<void(std::size_t, const std::string&)>& done) {
#ifdef GLINT_WITH_MPI
  if (size_ > 1) {
    if (rank_ == 0) {
      serveAndWork(size_, items, work, done);
    } else {
      workForRoot(work);
    }
    return;
  }
#endif
  runAll(items, work, done);
}

void Cluster::maxToRoot(std::vector<float>& values) {
#ifdef GLINT_WITH_MPI
  if (size_ > 1) reduceToRoot(values, MPI_FLOAT, MPI_MAX, rank_);
#else
  (void)values;
#endif
}

void Cluster::sumToRoot(std::vector<std::uint32_t>& values) {
#ifdef GLINT_WITH_MPI
  if (size_ > 1) reduceToRoot(values, MPI_UINT32_T, MPI_SUM, rank_);
#else
  (void)values;
#endif
}

std::vector<std::vector<std::byte>> Cluster::allGather(std::span<const std::byte> mine) {
#ifdef GLINT_WITH_MPI
  if (size_ > 1) {
    if (mine.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
      throw std::runtime_error("MPI: more than 2 GB to exchange in one level");
    }
    const int count = static_cast<int>(mine.size());
    std::vector<int> counts(static_cast<std::size_t>(size_)), offsets(counts.size());
    check(MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD),
          "allgather");
    std::size_t total = 0;
    for (std::size_t r = 0; r < counts.size(); ++r) {
      offsets[r] = static_cast<int>(total);
      total += static_cast<std::size_t>(counts[r]);
      if (total > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
        throw std::runtime_error("MPI: more than 2 GB to exchange in one level");
      }
    }
    std::vector<std::byte> all(total);
    check(MPI_Allgatherv(mine.data(), count, MPI_BYTE, all.data(), counts.data(), offsets.data(),
                         MPI_BYTE, MPI_COMM_WORLD),
          "allgatherv");
    std::vector<std::vector<std::byte>> out(counts.size());
    for (std::size_t r = 0; r < counts.size(); ++r) {
      out[r].assign(all.begin() + offsets[r], all.begin() + offsets[r] + counts[r]);
    }
    return out;
  }
#endif
  return {std::vector<std::byte>(mine.begin(), mine.end())};
}

void Cluster::abort(int status) {
#ifdef GLINT_WITH_MPI
  if (mpi_) MPI_Abort(MPI_COMM_WORLD, status);
#endif
  std::exit(status);
}

}  // namespace glint
