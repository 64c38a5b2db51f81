#include "insdiag/engine/analysis_cache.h"

#include <iterator>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <utility>

#include "analysis/prepared_run.h"

namespace insdiag::engine {

struct AnalysisCache::Impl {
  // One run's preparation for one set of a-priori inputs, and model A's
  // outcome for each identified base an Add started from.
  struct Entry {
    std::string run;
    std::optional<ErrorModel> nominal;
    std::vector<std::string> baseline_effects;
    std::shared_ptr<const pipeline::PreparedRun> prepared;
    std::map<std::string, std::shared_ptr<const pipeline::ModelAOutcome>> models_a;
    std::size_t bytes = 0;
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

  // Drops the least recently used entries until the bound holds. Under `mutex`.
  void Trim() {
    while (bytes > capacity_bytes && !entries.empty()) {
      bytes -= entries.back().bytes;
      entries.pop_back();
    }
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
  EntryModelAOutcomes(Impl& cache, std::string run, const AnalysisRequest& request,
                      std::string identified_base)
      : cache_(cache), run_(std::move(run)), request_(request), base_(std::move(identified_base)) {}

  std::shared_ptr<const pipeline::ModelAOutcome> Find() const override {
    std::lock_guard lock(cache_.mutex);
    const auto entry = cache_.Find(run_, request_);
    if (entry == cache_.entries.end()) return nullptr;
    const auto it = entry->models_a.find(base_);
    if (it == entry->models_a.end()) return nullptr;
    ++cache_.counts.models_a_reused;
    return it->second;
  }

  void Keep(std::shared_ptr<const pipeline::ModelAOutcome> outcome) override {
    std::lock_guard lock(cache_.mutex);
    const auto entry = cache_.Find(run_, request_);
    if (entry == cache_.entries.end() || entry->models_a.contains(base_)) return;
    const std::size_t added = outcome->Bytes();
    entry->models_a.emplace(base_, std::move(outcome));
    ++cache_.counts.models_a_kept;
    entry->bytes += added;
    cache_.bytes += added;
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
    const std::string& run_key, const std::function<absl::StatusOr<BenchRun>()>& read_run,
    const AnalysisRequest& request, const AnalysisOptions& options) {
  {
    std::lock_guard lock(impl_->mutex);
    if (const auto entry = impl_->Find(run_key, request); entry != impl_->entries.end()) {
      ++impl_->counts.preparations_reused;
      return entry->prepared;
    }
  }
  auto run = read_run();
  if (!run.ok()) return run.status();
  auto made = pipeline::PrepareRun(*std::move(run), request, options);
  if (!made.ok()) return made.status();
  std::shared_ptr<const pipeline::PreparedRun> prepared(*std::move(made));
  std::lock_guard lock(impl_->mutex);
  ++impl_->counts.preparations_made;
  const std::size_t size = prepared->Bytes();
  // Another analysis of the same inputs may have kept its preparation first.
  if (size <= impl_->capacity_bytes && impl_->Find(run_key, request) == impl_->entries.end()) {
    impl_->entries.push_front({run_key, request.nominal, request.baseline_effects, prepared, {}, size});
    impl_->bytes += size;
    impl_->Trim();
  }
  return prepared;
}

absl::StatusOr<Analysis> AnalysisCache::Analyze(const AnalysisCacheKeys& keys,
                                                const std::function<absl::StatusOr<BenchRun>()>& read_run,
                                                const AnalysisRequest& request, const AnalysisOptions& options) {
  auto prepared = Prepared(keys.run, read_run, request, options);
  if (!prepared.ok()) return prepared.status();
  if (keys.identified_base.empty()) return pipeline::AnalyzePrepared(**prepared, request, options, nullptr);
  Impl::EntryModelAOutcomes outcomes(*impl_, keys.run, request, keys.identified_base);
  return pipeline::AnalyzePrepared(**prepared, request, options, &outcomes);
}

absl::Status AnalysisCache::KeepModelA(const AnalysisCacheKeys& keys,
                                       const std::function<absl::StatusOr<BenchRun>()>& read_run,
                                       const AnalysisRequest& request, const AnalysisOptions& options) {
  if (keys.identified_base.empty() || !request.identified_base.has_value()) {
    return absl::InvalidArgumentError("model A is kept for an identified base only");
  }
  auto prepared = Prepared(keys.run, read_run, request, options);
  if (!prepared.ok()) return prepared.status();
  Impl::EntryModelAOutcomes outcomes(*impl_, keys.run, request, keys.identified_base);
  return pipeline::ModelAOutcomeOf(**prepared, request, options, &outcomes).status();
}

}  // namespace insdiag::engine
