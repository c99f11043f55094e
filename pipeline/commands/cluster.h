#pragma once
/// @file
/// @brief The processes a study or a field runs on: this one alone, or the ranks of an MPI job
/// (`mpirun -np N glint batch|run ...`, `srun glint ...`). Without MPI at build time, or when
/// not started by an MPI launcher, it is one process and calls no MPI at all.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "observers/point_set.h"

namespace glint {

class Cluster : public PointExchange {
 public:
  /// @brief Joins the MPI job when glint was built with MPI and an MPI launcher started it.
  Cluster();
  /// @brief Leaves the MPI job (MPI_Finalize).
  ~Cluster();
  Cluster(const Cluster&) = delete;
  Cluster& operator=(const Cluster&) = delete;

  [[nodiscard]] int rank() const override { return rank_; }
  [[nodiscard]] int size() const override { return size_; }
  /// @brief Whether this build can join an MPI job at all.
  [[nodiscard]] static bool mpiBuilt();

  /// @brief Runs the items of @p items (rank 0's list; other ranks pass anything) on all
  /// ranks: each rank takes the next item whenever it is free, so long items do not hold up
  /// a rank that has finished short ones (balanced by cost, not count). work(item) runs on
  /// the rank that took it and returns a record; on rank 0, done(item, record) is called for
  /// every item of every rank as it finishes, on the calling thread. Rank 0 computes too: its
  /// items run on a second thread while the calling thread answers the other ranks.
  void shareOut(const std::vector<std::size_t>& items,
                const std::function<std::string(std::size_t)>& work,
                const std::function<void(std::size_t, const std::string&)>& done);

  /// @brief Element-wise maximum of every rank's @p values, into rank 0's (exact: no rounding).
  void maxToRoot(std::vector<float>& values);
  /// @brief Element-wise sum of every rank's @p values, into rank 0's.
  void sumToRoot(std::vector<std::uint32_t>& values);

  /// @brief Every rank's bytes to every rank, in rank order (MPI_Allgatherv; the calling thread
  /// must be the one that joined the job). One process: its own bytes.
  std::vector<std::vector<std::byte>> allGather(std::span<const std::byte> mine) override;

  /// @brief Ends every rank of the job with @p status (after an error on one of them).
  [[noreturn]] void abort(int status);

 private:
  int rank_ = 0;
  int size_ = 1;
  bool mpi_ = false;  ///< MPI was initialised here (and is finalised by the destructor)
};

}  // namespace glint
