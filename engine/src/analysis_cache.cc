#include "insdiag/engine/analysis_cache.h"

#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <utility>

#include "analysis/prepared_run.h"

namespace insdiag::engine {

struct AnalysisCache::Impl {
  // One run's preparation for one nominal model and baseline, and model A's
  // outcome for each identified base an Add started from.
  struct Entry {
    std::string run;
    std::optional<ErrorModel> nominal;
    std::vector<std::string> baseline_effects;
    std::shared_ptr<const pipeline::PreparedRun> prepared;
    std::map<std::string, std::shared_ptr<const pipeline::ModelAOutcome>> models_a;
    std::size_t bytes = 0;  // the epochs' and models A's; the screened run is counted once for all entries
  };
  using Entries = std::list<Entry>;  // most recently used first

  explicit Impl(std::size_t capacity) : capacity_bytes(capacity) {}

  // The entry for these inputs, moved to the front; end() if none. Under `mutex`.
  Entries::iterator Find(const std::string& run, const AnalysisRequest& request) {
    for (auto it = entries.begin(); it != entries.end(); ++it) {
      if (it->run == run && it->nominal == request.nominal && it->baseline_effects == request.baseline_effects) {
        entries.splice(entries.begin(), entries, it);
        return entries.begin();
      }
    }
    return entries.end();
  }

  // The run screened for this nominal model under any baseline; null if
  // none is kept. Under `mutex`.
  std::shared_ptr<const pipeline::ScreenedRun> FindScreened(const std::string& run,
                                                            const AnalysisRequest& request) const {
    for (const Entry& e : entries) {
      if (e.run == run && e.nominal == request.nominal) return e.prepared->screened;
    }
    return nullptr;
  }

  // Keeps `prepared` unless an entry for the same inputs came first or it
  // exceeds the whole bound. Under `mutex`.
  void KeepPrepared(const std::string& run, const AnalysisRequest& request,
                    std::shared_ptr<const pipeline::PreparedRun> prepared) {
    const std::size_t size = prepared->EpochBytes();
    if (size + prepared->screened->Bytes() > capacity_bytes || Find(run, request) != entries.end()) return;
    entries.push_front({run, request.nominal, request.baseline_effects, std::move(prepared), {}, size});
    Trim();
  }

  // What the entries hold: their own bytes, and each screened run once.
  std::size_t Total() const {
    std::size_t total = 0;
    std::set<const pipeline::ScreenedRun*> screened;
    for (const Entry& e : entries) {
      total += e.bytes;
      if (screened.insert(e.prepared->screened.get()).second) total += e.prepared->screened->Bytes();
    }
    return total;
  }

  // Drops the least recently used entries until the bound holds. Under `mutex`.
  void Trim() {
    while (Total() > capacity_bytes && !entries.empty()) entries.pop_back();
    bytes = Total();
  }

  class EntryModelAOutcomes;

  const std::size_t capacity_bytes;
  mutable std::mutex mutex;
  Entries entries;
  std::size_t bytes = 0;
  Counts counts;
};

// Model A's outcomes of one run's entry, looked up again under the lock at
// each use: the entry may have left the cache meanwhile.
class AnalysisCache::Impl::EntryModelAOutcomes final : public pipeline::ModelAOutcomes {
 public:
  EntryModelAOutcomes(Impl& cache, std::string run, const AnalysisRequest& request, std::string identified_base)
      : cache_(cache), run_(std::move(run)), request_(request), base_(std::move(identified_base)) {}

  std::shared_ptr<const pipeline::ModelAOutcome> Find() const override {
    std::lock_guard lock(cache_.mutex);
    const auto entry = cache_.Find(run_, request_);
    if (entry == cache_.entries.end()) return nullptr;
    const auto it = entry->models_a.find(base_);
    return it == entry->models_a.end() ? nullptr : it->second;
  }

  void Reused() override {
    std::lock_guard lock(cache_.mutex);
    ++cache_.counts.models_a_reused;
  }

  void Keep(std::shared_ptr<const pipeline::ModelAOutcome> outcome) override {
    std::lock_guard lock(cache_.mutex);
    const auto entry = cache_.Find(run_, request_);
    if (entry == cache_.entries.end()) return;
    std::size_t bytes = entry->bytes + outcome->Bytes();
    if (const auto old = entry->models_a.find(base_); old != entry->models_a.end()) bytes -= old->second->Bytes();
    // Not at the cost of the preparation it was computed on.
    if (bytes + entry->prepared->screened->Bytes() > cache_.capacity_bytes) return;
    entry->bytes = bytes;
    entry->models_a[base_] = std::move(outcome);
    ++cache_.counts.models_a_kept;
    cache_.Trim();
  }

 private:
  Impl& cache_;
  const std::string run_;
  const AnalysisRequest& request_;
  const std::string base_;
};

AnalysisCache::AnalysisCache(std::size_t capacity_bytes) : impl_(std::make_unique<Impl>(capacity_bytes)) {}
AnalysisCache::~AnalysisCache() = default;

AnalysisCache::Counts AnalysisCache::counts() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->counts;
}

std::size_t AnalysisCache::bytes() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->bytes;
}

absl::StatusOr<std::shared_ptr<const pipeline::PreparedRun>> AnalysisCache::Prepared(
    const std::string& run_key, const std::function<absl::StatusOr<BenchRun>()>* read_run,
    const AnalysisRequest& request, const AnalysisOptions& options) {
  std::shared_ptr<const pipeline::ScreenedRun> screened;
  {
    std::lock_guard lock(impl_->mutex);
    if (const auto entry = impl_->Find(run_key, request); entry != impl_->entries.end()) {
      ++impl_->counts.preparations_reused;
      return entry->prepared;
    }
    screened = impl_->FindScreened(run_key, request);
  }
  if (screened == nullptr && read_run == nullptr) return nullptr;
  const bool screens = screened == nullptr;
  absl::StatusOr<std::unique_ptr<pipeline::PreparedRun>> made;
  if (screens) {
    auto run = (*read_run)();
    if (!run.ok()) return run.status();
    made = pipeline::PrepareRun(*std::move(run), request, options);
  } else {
    made = pipeline::PrepareRun(std::move(screened), request);
  }
  if (!made.ok()) return made.status();
  std::shared_ptr<const pipeline::PreparedRun> prepared(*std::move(made));
  std::lock_guard lock(impl_->mutex);
  ++(screens ? impl_->counts.preparations_made : impl_->counts.screenings_reused);
  impl_->KeepPrepared(run_key, request, prepared);
  return prepared;
}

absl::StatusOr<Analysis> AnalysisCache::Analyze(const AnalysisCacheKeys& keys,
                                                const std::function<absl::StatusOr<BenchRun>()>& read_run,
                                                const AnalysisRequest& request, const AnalysisOptions& options) {
  auto prepared = Prepared(keys.run, &read_run, request, options);
  if (!prepared.ok()) return prepared.status();
  if (keys.identified_base.empty()) return pipeline::AnalyzePrepared(**prepared, request, options, nullptr);
  Impl::EntryModelAOutcomes outcomes(*impl_, keys.run, request, keys.identified_base);
  return pipeline::AnalyzePrepared(**prepared, request, options, &outcomes);
}

absl::StatusOr<bool> AnalysisCache::KeepModelA(const AnalysisCacheKeys& keys, const AnalysisRequest& request,
                                               const AnalysisOptions& options) {
  if (keys.identified_base.empty() || !request.identified_base.has_value()) {
    return absl::InvalidArgumentError("model A is kept for an identified base only");
  }
  auto prepared = Prepared(keys.run, nullptr, request, options);
  if (!prepared.ok()) return prepared.status();
  if (*prepared == nullptr) return false;
  Impl::EntryModelAOutcomes outcomes(*impl_, keys.run, request, keys.identified_base);
  auto outcome = pipeline::ModelAOutcomeOf(**prepared, request, options, &outcomes);
  if (!outcome.ok()) return outcome.status();
  return true;
}

}  // namespace insdiag::engine
