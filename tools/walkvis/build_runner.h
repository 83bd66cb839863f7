// Where `walkvis build` builds its view cells: this process's threads, and under mpirun every
// rank's (OpenMPI), with a journal that lets a killed build go on. See build_runner.cpp.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "pfd_hfd/pfd.h"
#include "pfd_hfd/pfd_journal.h"

namespace walkvis {

// This process's place in an MPI job. Set up only when the process was started by mpirun (its
// environment says so): the same binary runs alone without it. MPI_Finalize on destruction.
class MpiWorld {
 public:
  MpiWorld();  // MPI_Init_thread (funneled: only this thread calls MPI) when under mpirun
  ~MpiWorld();
  MpiWorld(const MpiWorld&) = delete;
  MpiWorld& operator=(const MpiWorld&) = delete;
  bool active() const { return active_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  int localSize() const { return local_size_; }  // ranks on this machine
  // Ends every rank of the job with `status` (MPI_Abort): for an error that leaves ranks waiting.
  [[noreturn]] void abort(int status) const;

 private:
  bool active_ = false;
  int rank_ = 0, size_ = 1, local_size_ = 1;
};

// Eyes at which each of `cells` view cells has its queries timed (timePfdQueries) for the build's
// report: about 100,000 for them all, 64 to 2,000 each, never over stat_eyes (0: none). The BSP
// traversal it times costs tens of µs an eye at 20k fragments, and freedoom2 MAP12's several
// hundred cells spent minutes at 2,000 each.
uint32_t queryTimingEyes(uint32_t stat_eyes, size_t cells);

// buildPfdCell, then (when it made a tree) its queries timed at `timing_eyes` eyes into
// stats.query_timing: what a build's slot does with a job, and what `walkvis plan` measures.
PfdCellOutcome buildTimedPfdCell(const PfdCellContext& context, const PfdCellJob& job, uint32_t timing_eyes,
                                 const std::function<void(double)>& progress = {});

// Rank 0's side of a build (the only side without MPI): a PfdCellRunner that hands the jobs of each
// round out, the costliest first, to `threads` local slots and to every other rank's slots as each
// asks for more (dynamic assignment: the cost estimates are poor for HFD cells), skips the jobs the
// journal has and journals the others as they finish, and prints progress (cells done / planned,
// rays per second, an ETA, per rank). Destruction tells the other ranks to stop.
class CellScheduler {
 public:
  CellScheduler(const PfdCellContext& context, const MpiWorld& world, uint32_t threads, PfdJournal* journal,
                std::function<void(const std::string&)> progress);
  ~CellScheduler();
  CellScheduler(const CellScheduler&) = delete;
  CellScheduler& operator=(const CellScheduler&) = delete;
  PfdCellRunner runner();
  // Every rank's rays and cells so far, one line.
  std::string summary() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// A rank other than 0: builds the jobs rank 0 sends on `threads` slots until it says stop.
void serveCells(const PfdCellContext& context, const MpiWorld& world, uint32_t threads);

}  // namespace walkvis
