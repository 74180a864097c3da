// Tabulation of the two-sphere resistance functions in u = ln(xi) with 6-point Lagrange
// interpolation (see resistance_table.hpp for the mathematics and error estimate).

#include "lubrication/resistance_table.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

namespace stokesian::lubrication {

namespace {
// Lagrange weights of the 6-point stencil with nodes at 0..5, evaluated at x:
// w_m = prod_{l != m} (x - l) / (m - l).
void lagrange6(double x, double w[6]) {
  static const double denom[6] = {-120.0, 24.0, -12.0, 12.0, -24.0, 120.0};
  for (int m = 0; m < 6; ++m) {
    double p = 1.0;
    for (int l = 0; l < 6; ++l)
      if (l != m) p *= (x - l);
    w[m] = p / denom[m];
  }
}

// Lagrange weights of the n-point stencil with nodes at 0..n-1 (n <= 10), evaluated at x.
void lagrange_n(int n, double x, double* w) {
  for (int m = 0; m < n; ++m) {
    double p = 1.0, q = 1.0;
    for (int l = 0; l < n; ++l)
      if (l != m) {
        p *= (x - l);
        q *= double(m - l);
      }
    w[m] = p / q;
  }
}

// Range and step in u = ln(xi) of every table of the cache (the ResistanceTable defaults).
constexpr double kXiMin = 1e-8, kXiMax = 1e3, kStep = 0.025;
}  // namespace

ResistanceTable::ResistanceTable(double lambda, double xi_min, double xi_max, double step,
                                 int order)
    : series_(lambda, order), xi_min_(xi_min), xi_max_(xi_max) {
  if (!(xi_min > 0.0) || !(xi_max > xi_min) || !(step > 0.0))
    throw std::invalid_argument("ResistanceTable: bad range");
  u0_ = std::log(xi_min);
  const double u1 = std::log(xi_max);
  n_ = static_cast<int>(std::ceil((u1 - u0_) / step)) + 1;
  n_ = std::max(n_, 6);
  h_ = (u1 - u0_) / (n_ - 1);
  values_.resize(static_cast<std::size_t>(n_) * kNumScalars);
  for (int j = 0; j < n_; ++j) {
    const ResistanceScalars r = series_.at_gap(std::exp(u0_ + j * h_));
    for (int i = 0; i < kNumScalars; ++i)
      values_[static_cast<std::size_t>(j) * kNumScalars + i] = scalar_at(r, i);
  }
}

ResistanceScalars ResistanceTable::at_gap(double xi) const {
  if (!(xi > 0.0)) throw std::invalid_argument("ResistanceTable: xi must be > 0");
  if (xi < xi_min_ || xi > xi_max_) return series_.at_gap(xi);
  const double v = (std::log(xi) - u0_) / h_;
  int j0 = static_cast<int>(std::floor(v)) - 2;  // nodes j0 .. j0+5
  j0 = std::clamp(j0, 0, n_ - 6);
  const double x = v - j0;  // position in node units, nodes at 0..5
  double w[6];
  lagrange6(x, w);
  ResistanceScalars out{};
  const double* base = &values_[static_cast<std::size_t>(j0) * kNumScalars];
  for (int i = 0; i < kNumScalars; ++i) {
    double acc = 0.0;
    for (int m = 0; m < 6; ++m) acc += w[m] * base[m * kNumScalars + i];
    scalar_at(out, i) = acc;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Cache.  Each table lives in an Entry created under mutex_ and built once (std::call_once)
// outside it, so different tables are built concurrently by the threads that need them and a
// thread needing a table under construction waits for it.

ResistanceTableCache::ResistanceTableCache(double log_lambda_step, int stencil, int order)
    : h_(log_lambda_step), stencil_(stencil), order_(order) {
  if (!(log_lambda_step > 0.0) || !(log_lambda_step <= 1.0))
    throw std::invalid_argument("ResistanceTableCache: log-lambda step must be in (0, 1]");
  if (stencil < 2 || stencil > kMaxStencil || stencil % 2)
    throw std::invalid_argument("ResistanceTableCache: stencil must be even, 2..10");
}

int ResistanceTableCache::order_of(double lambda) const {
  return order_ > 0 ? order_ : ResistanceSeries::default_order(lambda);
}

double ResistanceTableCache::node(int k) const { return std::exp(static_cast<double>(k) * h_); }

ResistanceTableCache::Entry& ResistanceTableCache::entry_locked(const Key& key) {
  auto it = tables_.find(key);
  if (it == tables_.end()) it = tables_.emplace(key, std::make_unique<Entry>()).first;
  return *it->second;
}

namespace {
// Process-wide store of built tables (immutable, keyed by (lambda, order); deterministic
// construction, so sharing does not change any result).  Bounded to the last 128 inserted;
// the caches keep their own references, so eviction only costs a rebuild elsewhere.
std::shared_ptr<const ResistanceTable> shared_table(double lambda, int order) {
  static std::mutex mutex;
  static std::map<std::pair<double, int>, std::pair<std::shared_ptr<const ResistanceTable>, long>> store;
  static long counter = 0;
  const auto key = std::make_pair(lambda, order);
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = store.find(key);
    if (it != store.end()) return it->second.first;
  }
  auto table = std::make_shared<const ResistanceTable>(lambda, kXiMin, kXiMax, kStep, order);
  std::lock_guard<std::mutex> lock(mutex);
  auto it = store.find(key);
  if (it != store.end()) return it->second.first;  // built concurrently elsewhere: same values
  if (store.size() >= 128) {
    auto oldest = store.begin();
    for (auto jt = store.begin(); jt != store.end(); ++jt)
      if (jt->second.second < oldest->second.second) oldest = jt;
    store.erase(oldest);
  }
  store.emplace(key, std::make_pair(table, counter++));
  return table;
}
}  // namespace

const ResistanceTable& ResistanceTableCache::built(Entry& e, const Key& key) {
  std::call_once(e.once, [&] {
    e.table = shared_table(key.first, key.second);
    e.ready.store(true, std::memory_order_release);
  });
  return *e.table;
}

bool ResistanceTableCache::is_exact_locked(double lambda, long& k) const {
  k = std::lround(std::log(lambda) / h_);
  if (lambda == node(static_cast<int>(k))) return true;
  return exact_.count(lambda) > 0;
}

bool ResistanceTableCache::is_exact(double lambda) const {
  std::lock_guard<std::mutex> lock(mutex_);
  long k;
  return is_exact_locked(lambda, k);
}

const ResistanceTable& ResistanceTableCache::get(double lambda) {
  if (!(lambda > 0.0) || !std::isfinite(lambda))
    throw std::invalid_argument("ResistanceTableCache: lambda must be positive");
  const Key key{lambda, order_of(lambda)};
  Entry* e;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    e = &entry_locked(key);
  }
  return built(*e, key);
}

void ResistanceTableCache::set_exact_ratios(const std::vector<double>& lambdas) {
  for (double l : lambdas)
    if (!(l > 0.0) || !std::isfinite(l))
      throw std::invalid_argument("ResistanceTableCache: lambda must be positive");
  std::vector<std::pair<Key, Entry*>> todo;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    exact_ = std::set<double>(lambdas.begin(), lambdas.end());
    for (double l : exact_) {
      const Key key{l, order_of(l)};
      todo.emplace_back(key, &entry_locked(key));
    }
  }
  build_all(todo);
}

bool ResistanceTableCache::prepare_radii(const std::vector<double>& radii) {
  std::vector<double> r(radii);
  std::sort(r.begin(), r.end());
  r.erase(std::unique(r.begin(), r.end()), r.end());
  const std::size_t n = r.size();
  std::set<double> lambdas;  // distinct ratios a_j/a_i, a_i != a_j (n (n - 1) at most)
  if (n <= 64)
    for (std::size_t i = 0; i < n && lambdas.size() <= kMaxExactRatios; ++i)
      for (std::size_t j = 0; j < n; ++j)
        if (i != j) lambdas.insert(r[j] / r[i]);
  if (n > 64 || lambdas.size() > kMaxExactRatios) {
    set_exact_ratios({});
    return false;
  }
  set_exact_ratios(std::vector<double>(lambdas.begin(), lambdas.end()));
  return true;
}

std::size_t ResistanceTableCache::num_tables() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::size_t n = 0;
  for (const auto& kv : tables_) n += kv.second->ready.load(std::memory_order_acquire);
  return n;
}

int ResistanceTableCache::stencil_locked(double lambda, Key* keys, Entry** entries, double* w) {
  if (!(lambda > 0.0) || !std::isfinite(lambda))
    throw std::invalid_argument("ResistanceTableCache: lambda must be positive");
  const int order = order_of(lambda);
  long k;
  if (is_exact_locked(lambda, k)) {
    keys[0] = Key{lambda, order};
    entries[0] = &entry_locked(keys[0]);
    w[0] = 1.0;
    return 1;
  }
  const double v = std::log(lambda) / h_;
  const long j0 = static_cast<long>(std::floor(v)) - (stencil_ / 2 - 1);  // nodes j0 .. j0+n-1
  lagrange_n(stencil_, v - static_cast<double>(j0), w);
  for (int m = 0; m < stencil_; ++m) {
    keys[m] = Key{node(static_cast<int>(j0 + m)), order};
    entries[m] = &entry_locked(keys[m]);
  }
  return stencil_;
}

void ResistanceTableCache::build_all(const std::vector<std::pair<Key, Entry*>>& todo) {
#pragma omp parallel for schedule(dynamic, 1) if (todo.size() > 1)
  for (long i = 0; i < long(todo.size()); ++i)
    built(*todo[std::size_t(i)].second, todo[std::size_t(i)].first);
}

void ResistanceTableCache::prefetch(const std::vector<double>& lambdas) {
  std::vector<std::pair<Key, Entry*>> todo;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    std::set<Key> seen;
    Key keys[kMaxStencil];
    Entry* entries[kMaxStencil];
    double w[kMaxStencil];
    for (double l : lambdas) {
      const int n = stencil_locked(l, keys, entries, w);
      for (int m = 0; m < n; ++m)
        if (!entries[m]->ready.load(std::memory_order_acquire) && seen.insert(keys[m]).second)
          todo.emplace_back(keys[m], entries[m]);
    }
  }
  build_all(todo);
}

ResistanceScalars ResistanceTableCache::scalars(double lambda, double xi) {
  Key keys[kMaxStencil];
  Entry* entries[kMaxStencil];
  double w[kMaxStencil];
  int n = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    n = stencil_locked(lambda, keys, entries, w);
  }
  if (n == 1) return built(*entries[0], keys[0]).at_gap(xi);
  ResistanceScalars node_values[kMaxStencil];
  for (int m = 0; m < n; ++m) node_values[m] = built(*entries[m], keys[m]).at_gap(xi);
  ResistanceScalars out{};
  for (int i = 0; i < kNumScalars; ++i) {
    double acc = 0.0;
    for (int m = 0; m < n; ++m) acc += w[m] * scalar_at(node_values[m], i);
    scalar_at(out, i) = acc;
  }
  return out;
}

void ResistanceTableCache::pair_scalars(double r, double a1, double a2, ResistanceScalars& s11_12,
                                        ResistanceScalars& s22_21) {
  const double xi = 2.0 * r / (a1 + a2) - 2.0;
  s11_12 = scalars(a2 / a1, xi);
  s22_21 = relabel_spheres(scalars(a1 / a2, xi));
}

}  // namespace stokesian::lubrication
