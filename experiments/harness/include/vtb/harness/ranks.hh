#pragma once
/// \file
/// The harness beyond one process: the ranks of `mpirun -np N vtb study|sweep` (MPI_COMM_WORLD
/// when the process was started by a launcher, else one rank), the cells of a study handed out
/// to them, the reference sent to all, the rows gathered on rank 0; and the static split of a
/// study into the parts of a job array (`--shard K/N`). Rank 0 alone prints and writes.

#include <memory>
#include <string>
#include <vector>

namespace vtb::harness {

/// This process's rank and the number of ranks (0 and 1 without MPI).
struct Ranks {
  int rank = 0, size = 1;
  bool root() const { return rank == 0; }
};
Ranks world();

/// Under mpirun with several ranks: ends every rank with `code` (a rank that failed must not
/// leave the others waiting for it in a collective). Without MPI, returns `code`.
int end_all_ranks(int code);

/// Hands out cell indices 0..count-1 to whichever rank asks first (MPI one-sided fetch-and-add
/// on a counter that rank 0 holds; a plain counter on one rank). Cells are taken in index order,
/// so list the costly ones first. Collective to make and to destroy, unless `across_ranks` is
/// false: then this rank takes every cell (a part of a larger job that one rank runs).
class CellQueue {
public:
  explicit CellQueue(long count, bool across_ranks = true);
  ~CellQueue();
  CellQueue(const CellQueue&) = delete;
  CellQueue& operator=(const CellQueue&) = delete;
  /// The next cell, or -1 when every cell has been taken.
  long next();

private:
  long m_count;
  long m_local = 0; ///< without MPI
  struct Window;    ///< the MPI window holding the counter (ranks.cc: no MPI in this header)
  std::unique_ptr<Window> m_window;
};

/// A vector of doubles sent from rank 0 to every rank without making the others wait for it:
/// they poll between cells (two non-blocking broadcasts: the size, then the data).
class Broadcast {
public:
  Broadcast(); ///< collective: every rank posts its receive of the size
  ~Broadcast();
  Broadcast(const Broadcast&) = delete;
  Broadcast& operator=(const Broadcast&) = delete;
  /// Rank 0: sends `data` and waits until it has gone out.
  void send(std::vector<double> data);
  /// Other ranks: whether the data has arrived (progresses the transfer); `wait` blocks for it.
  bool ready();
  void wait();
  const std::vector<double>& data() const { return m_data; }

private:
  struct Pending; ///< the MPI requests under way
  std::unique_ptr<Pending> m_pending;
  std::vector<double> m_data;
  long m_size = -1;
  bool m_done = false;
};

/// Waits until every rank is here (nothing without MPI).
void barrier();

/// Every rank's string, in rank order, on rank 0 (empty elsewhere). Collective.
std::vector<std::string> gather_on_root(const std::string& mine);

/// Where this rank runs, for the timing columns: "serial, cpus 0-1" or "rank 1/2 (2 on node0),
/// cpus 1". `shared` is set (on rank 0) when two ranks of one node may use the same core, so
/// that their step times may be each other's. Collective.
std::string binding(bool* shared = nullptr);

/// The static split of cells into `parts` by estimated cost (the costliest cell to the least
/// loaded part, ties to the lower part): part[i] of cell i. Deterministic.
std::vector<int> split_by_cost(const std::vector<double>& cost, int parts);

/// `--shard K/N`: K in 0..N-1. InputError naming the option otherwise.
struct Shard {
  int index = 0, count = 1;
  bool active() const { return count > 1; }
};
Shard parse_shard(const std::string& text);

} // namespace vtb::harness
