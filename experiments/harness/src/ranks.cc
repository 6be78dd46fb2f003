#include "vtb/harness/ranks.hh"

#include "vtb/base/input_error.hh"

#include <mpi.h>
#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

namespace vtb::harness {
namespace {

bool mpi_on() {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  return initialized && !finalized;
}

/// The cores this process may run on, as "0-1" or "1" or "0,2-3".
std::string cpu_list(std::set<int>* out = nullptr) {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return "?";
  std::vector<int> cpus;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) cpus.push_back(c);
  if (out) out->insert(cpus.begin(), cpus.end());
  std::ostringstream os;
  for (std::size_t i = 0; i < cpus.size();) {
    std::size_t j = i;
    while (j + 1 < cpus.size() && cpus[j + 1] == cpus[j] + 1) ++j;
    os << (i ? "," : "") << cpus[i];
    if (j > i) os << '-' << cpus[j];
    i = j + 1;
  }
  return os.str();
}

} // namespace

Ranks world() {
  Ranks r;
  if (!mpi_on()) return r;
  MPI_Comm_rank(MPI_COMM_WORLD, &r.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &r.size);
  return r;
}

int end_all_ranks(int code) {
  if (world().size > 1) MPI_Abort(MPI_COMM_WORLD, code);
  return code;
}

struct CellQueue::Window {
  MPI_Win win = MPI_WIN_NULL;
  long* counter = nullptr; ///< on rank 0
};

CellQueue::CellQueue(long count, bool across_ranks) : m_count(count) {
  if (world().size == 1 || !across_ranks) return;
  m_window = std::make_unique<Window>();
  const MPI_Aint bytes = world().root() ? static_cast<MPI_Aint>(sizeof(long)) : 0;
  MPI_Win_allocate(bytes, sizeof(long), MPI_INFO_NULL, MPI_COMM_WORLD, &m_window->counter, &m_window->win);
  if (world().root()) {
    MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, m_window->win);
    *m_window->counter = 0;
    MPI_Win_unlock(0, m_window->win);
  }
  MPI_Barrier(MPI_COMM_WORLD); // the counter is 0 before anyone takes a cell
}

CellQueue::~CellQueue() {
  if (m_window) MPI_Win_free(&m_window->win);
}

long CellQueue::next() {
  long taken = 0;
  if (!m_window) {
    taken = m_local++;
  } else {
    const long one = 1;
    MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, m_window->win);
    MPI_Fetch_and_op(&one, &taken, MPI_LONG, 0, 0, MPI_SUM, m_window->win);
    MPI_Win_unlock(0, m_window->win);
  }
  return taken < m_count ? taken : -1;
}

struct Broadcast::Pending {
  MPI_Request size = MPI_REQUEST_NULL, data = MPI_REQUEST_NULL;
};

Broadcast::Broadcast() {
  if (world().size == 1) return;
  m_pending = std::make_unique<Pending>();
  if (!world().root()) MPI_Ibcast(&m_size, 1, MPI_LONG, 0, MPI_COMM_WORLD, &m_pending->size);
}

Broadcast::~Broadcast() {
  if (m_pending && !world().root() && !m_done) wait();
}

void Broadcast::send(std::vector<double> data) {
  m_data = std::move(data);
  m_done = true;
  if (!m_pending) return;
  m_size = static_cast<long>(m_data.size());
  MPI_Ibcast(&m_size, 1, MPI_LONG, 0, MPI_COMM_WORLD, &m_pending->size);
  MPI_Wait(&m_pending->size, MPI_STATUS_IGNORE);
  MPI_Ibcast(m_data.data(), static_cast<int>(m_data.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD, &m_pending->data);
  MPI_Wait(&m_pending->data, MPI_STATUS_IGNORE);
}

bool Broadcast::ready() {
  if (m_done || !m_pending) return m_done;
  int flag = 0;
  if (m_size < 0) {
    MPI_Test(&m_pending->size, &flag, MPI_STATUS_IGNORE);
    if (!flag) return false;
    m_data.resize(static_cast<std::size_t>(m_size));
    MPI_Ibcast(m_data.data(), static_cast<int>(m_size), MPI_DOUBLE, 0, MPI_COMM_WORLD, &m_pending->data);
  }
  MPI_Test(&m_pending->data, &flag, MPI_STATUS_IGNORE);
  m_done = flag != 0;
  return m_done;
}

void Broadcast::wait() {
  if (m_done || !m_pending) return;
  if (m_size < 0) {
    MPI_Wait(&m_pending->size, MPI_STATUS_IGNORE);
    m_data.resize(static_cast<std::size_t>(m_size));
    MPI_Ibcast(m_data.data(), static_cast<int>(m_size), MPI_DOUBLE, 0, MPI_COMM_WORLD, &m_pending->data);
  }
  MPI_Wait(&m_pending->data, MPI_STATUS_IGNORE);
  m_done = true;
}

void barrier() {
  if (world().size > 1) MPI_Barrier(MPI_COMM_WORLD);
}

std::vector<std::string> gather_on_root(const std::string& mine) {
  const Ranks w = world();
  if (w.size == 1) return {mine};
  int n = static_cast<int>(mine.size());
  std::vector<int> sizes(static_cast<std::size_t>(w.size)), offsets(static_cast<std::size_t>(w.size));
  MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  if (w.root()) {
    std::exclusive_scan(sizes.begin(), sizes.end(), offsets.begin(), 0);
    all.resize(static_cast<std::size_t>(offsets.back() + sizes.back()));
  }
  MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
  std::vector<std::string> out;
  if (w.root())
    for (int r = 0; r < w.size; ++r)
      out.push_back(all.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                               static_cast<std::size_t>(sizes[static_cast<std::size_t>(r)])));
  return out;
}

std::string binding(bool* shared) {
  const Ranks w = world();
  std::set<int> mine;
  const std::string cpus = cpu_list(&mine);
  if (shared) *shared = false;
  if (w.size == 1) return "serial, cpus " + cpus;
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  // Every rank's host and cores, so that each can count the ranks on its node and rank 0 can
  // tell whether two of them may share a core.
  std::ostringstream me;
  me << host << ' ';
  for (int c : mine) me << c << ' ';
  const std::vector<std::string> all = gather_on_root(me.str());
  std::string table;
  if (w.root())
    for (const auto& s : all) table += s + '\n';
  long size = static_cast<long>(table.size());
  MPI_Bcast(&size, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  table.resize(static_cast<std::size_t>(size));
  MPI_Bcast(table.data(), static_cast<int>(size), MPI_CHAR, 0, MPI_COMM_WORLD);
  std::map<std::string, std::vector<std::set<int>>> nodes;
  std::istringstream in(table);
  for (std::string line; std::getline(in, line);) {
    std::istringstream l(line);
    std::string h;
    l >> h;
    std::set<int> cores;
    for (int c; l >> c;) cores.insert(c);
    nodes[h].push_back(cores);
  }
  const auto& here = nodes[host];
  if (shared)
    for (const auto& [h, sets] : nodes)
      for (std::size_t a = 0; a < sets.size(); ++a)
        for (std::size_t b = a + 1; b < sets.size(); ++b)
          for (int c : sets[a])
            if (sets[b].count(c)) *shared = true;
  std::ostringstream os;
  os << "rank " << w.rank << '/' << w.size << " (" << here.size() << " on " << host << "), cpus " << cpus;
  return os.str();
}

std::vector<int> split_by_cost(const std::vector<double>& cost, int parts) {
  std::vector<std::size_t> order(cost.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
  std::vector<double> load(static_cast<std::size_t>(std::max(parts, 1)), 0.0);
  std::vector<int> part(cost.size(), 0);
  for (std::size_t i : order) {
    const auto p = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    part[i] = static_cast<int>(p);
    load[p] += cost[i];
  }
  return part;
}

Shard parse_shard(const std::string& text) {
  Shard s;
  const auto slash = text.find('/');
  char* end = nullptr;
  bool ok = slash != std::string::npos;
  if (ok) {
    s.index = static_cast<int>(std::strtol(text.c_str(), &end, 10));
    ok = end == text.c_str() + slash;
    s.count = static_cast<int>(std::strtol(text.c_str() + slash + 1, &end, 10));
    ok = ok && *end == '\0' && end != text.c_str() + slash + 1;
  }
  if (!ok || s.count < 1 || s.index < 0 || s.index >= s.count)
    throw InputError("--shard \"" + text + "\": expected K/N with 0 <= K < N (the K-th of N parts)");
  return s;
}

} // namespace vtb::harness
