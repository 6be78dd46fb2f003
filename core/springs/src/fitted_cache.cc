#include "vtb/springs/fitted_cache.hh"

#include "vtb/base/atomic_file.hh"
#include "vtb/springs/fitted_springs.hh"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

namespace vtb {
namespace {

constexpr char kMagic[8] = {'V', 'T', 'B', 'F', 'I', 'T', 'B', '\n'}; // the file's format: bump when it changes

/// The SHA-256 of the fit's sources (CMake hashes them, core/springs/CMakeLists.txt): a fit
/// cached by another version of the code that computes it is not read back.
constexpr char kCode[] = VTB_FIT_CODE_SHA256;
constexpr std::size_t kCodeSize = sizeof kCode - 1;
static_assert(kCodeSize == 64, "VTB_FIT_CODE_SHA256 is 64 hex digits");

struct Fnv {
  std::uint64_t h = 1469598103934665603ULL;
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ULL;
  }
  void add(double x) { add(&x, sizeof x); }
};

/// The fit is equivariant in E t (its FEM, its priors, its loads scale with E t, its answers
/// do not), so the key holds nu and not E or t: one fit per mesh, Poisson ratio and supports,
/// and a stiffness sweep or the viewer's stiffness slider reads it back scaled.
template <int dim>
std::uint64_t key(const Mesh<dim>& mesh, double nu, const std::vector<int>& supports, const std::string& target,
                  bool volume, double cell_shear, bool nodal, const Eigen::MatrixXd& own_loads) {
  Fnv f;
  f.add(kMagic, sizeof kMagic);
  const int d = dim;
  f.add(&d, sizeof d);
  f.add(mesh.points.data(), sizeof(double) * static_cast<std::size_t>(mesh.points.size()));
  for (const auto& c : mesh.cells) f.add(c.data(), sizeof(int) * c.size());
  f.add(nu);
  const auto count = supports.size();
  f.add(&count, sizeof count);
  f.add(supports.data(), sizeof(int) * count);
  const FitOptions o;
  for (const double x : {double(o.modes), o.pull, o.floor, double(o.max_iterations), o.tolerance, o.weighting,
                         o.uniform_stress, double(o.cg_iterations), double(o.holdout), double(o.patience),
                         o.min_improvement, double(FitOptions::kEarlyStopDofs)})
    f.add(x);
  f.add(target.data(), target.size());
  if (volume) f.add("volume", 6); // the springs-only fits' keys stay as they were
  if (cell_shear > 0) f.add(cell_shear);
  if (nodal) f.add("nodal", 5);
  if (own_loads.cols() > 0) { // their shape, not their size: the fit scales them to its modes'
    f.add("own", 3);
    f.add(FitOptions::kOwnLoadWeight);
    // Each column at unit length, to 2^-32 (a scaled load's last bits differ: the same key).
    for (Eigen::Index c = 0; c < own_loads.cols(); ++c) {
      const Eigen::VectorXd unit = (own_loads.col(c).normalized() * 0x1p32).array().round().matrix();
      f.add(unit.data(), sizeof(double) * static_cast<std::size_t>(unit.size()));
    }
  }
  return f.h;
}

constexpr const char* kChosen[4] = {"fitted", "lloyd", "van-gelder", "volume"};

/// The index of `chosen` in kChosen (0, "fitted", for anything else).
int chosen_index(const std::string& chosen) {
  for (int i = 0; i < 4; ++i)
    if (chosen == kChosen[i]) return i;
  return 0;
}

/// The file: the magic, the fit's code version (kCode), which constants were chosen (an index
/// into kChosen) and their validation error (two doubles), then the constants (the springs',
/// then the cells' with a volume term).
bool read_cache(const std::filesystem::path& file, Eigen::VectorXd& k, CachedFit& info) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t head = sizeof kMagic + kCodeSize + 2 * sizeof(double);
  const std::size_t want = head + sizeof(double) * static_cast<std::size_t>(k.size());
  if (bytes.size() != want || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0 ||
      std::memcmp(bytes.data() + sizeof kMagic, kCode, kCodeSize) != 0)
    return false;
  double meta[2];
  std::memcpy(meta, bytes.data() + sizeof kMagic + kCodeSize, sizeof meta);
  std::memcpy(k.data(), bytes.data() + head, want - head);
  if (!(meta[0] == 0 || meta[0] == 1 || meta[0] == 2 || meta[0] == 3)) return false;
  info.chosen = kChosen[static_cast<int>(meta[0])];
  info.validation = meta[1];
  return k.allFinite() && (k.array() >= 0).all();
}

} // namespace

std::string fit_code_version() {
  return kCode;
}

std::filesystem::path fit_cache_dir() {
  if (const char* v = std::getenv("VTB_CACHE_DIR")) return v; // empty: off
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::filesystem::path(x) / "vtb";
  if (const char* h = std::getenv("HOME"); h && *h) return std::filesystem::path(h) / ".cache" / "vtb";
  return {};
}

template <int dim>
Eigen::VectorXd cached_fitted_stiffness(const Mesh<dim>& mesh, double E, double nu, double t,
                                        const std::vector<int>& supports, CachedFit* info, const FitProgress& progress,
                                        const FitTarget& target, Eigen::VectorXd* cell_stiffness, double cell_shear,
                                        bool nodal) {
  const std::filesystem::path dir = fit_cache_dir();
  const bool volume = cell_stiffness != nullptr;
  // The volume networks train on the scene's own loads where the continuum answers them.
  const Eigen::MatrixXd own = trains_on_own_loads(target, volume) ? target.own_loads : Eigen::MatrixXd();
  char name[40];
  std::snprintf(name, sizeof name, "fitted-%016llx.bin",
                static_cast<unsigned long long>(key(mesh, nu, supports, target.key, volume, cell_shear, nodal, own)));
  const auto ns = static_cast<Eigen::Index>(unique_edges(mesh).size());
  // The springs', then the cells' (or the nodes').
  Eigen::VectorXd k(ns + (volume ? (nodal ? mesh.num_nodes() : mesh.num_cells()) : 0));
  CachedFit got;
  got.hit = !dir.empty() && read_cache(dir / name, k, got);
  if (!got.hit) {
    FitOptions options;
    options.supports = supports;
    options.progress = progress;
    options.target = target;
    options.volume = volume;
    options.cell_shear = cell_shear;
    options.nodal = nodal;
    if (own.cols() > 0) options.own_load = FitOptions::kOwnLoadWeight;
    FitReport report;
    Eigen::VectorXd cells;
    k.head(ns) = fitted_stiffness(mesh, 1.0, nu, 1.0, options, &report, &cells); // unit E t, scaled below
    if (volume) k.tail(cells.size()) = cells;
    got.chosen = report.chosen;
    got.validation = report.validation();
    if (!dir.empty()) try {
        ensure_directory(dir);
        const double meta[2] = {static_cast<double>(chosen_index(report.chosen)), got.validation};
        write_file_atomically(dir / name, [&](std::ostream& os) {
          os.write(kMagic, sizeof kMagic);
          os.write(kCode, kCodeSize);
          os.write(reinterpret_cast<const char*>(meta), sizeof meta);
          os.write(reinterpret_cast<const char*>(k.data()), static_cast<std::streamsize>(sizeof(double) * k.size()));
        });
      } catch (const std::exception&) { // best effort: a read-only or full cache is passed over
      }
  }
  if (info) *info = got;
  const double scale = E * (dim == 2 ? t : 1.0);
  if (volume) *cell_stiffness = scale * k.tail(k.size() - ns);
  return scale * k.head(ns);
}

template Eigen::VectorXd cached_fitted_stiffness<2>(const Mesh<2>&, double, double, double, const std::vector<int>&,
                                                    CachedFit*, const FitProgress&, const FitTarget&, Eigen::VectorXd*,
                                                    double, bool);
template Eigen::VectorXd cached_fitted_stiffness<3>(const Mesh<3>&, double, double, double, const std::vector<int>&,
                                                    CachedFit*, const FitProgress&, const FitTarget&, Eigen::VectorXd*,
                                                    double, bool);

} // namespace vtb
