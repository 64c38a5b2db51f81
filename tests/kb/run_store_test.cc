#include "insdiag/kb/run_store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/database_fixture.h"
#include "support/synthetic_run.h"

namespace insdiag::kb {
namespace {

using ::testing::HasSubstr;

class RunStoreTest : public testing::DatabaseTest {
 protected:
  void SetUp() override {
    DatabaseTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    store_ = std::make_unique<RunStore>(pool());
  }
  std::unique_ptr<RunStore> store_;
};

UploadIdentity Identity(std::string sha256, std::string request_id = "", std::string fingerprint = "") {
  UploadIdentity identity;
  identity.sha256 = std::move(sha256);
  identity.request_id = std::move(request_id);
  identity.request_fingerprint = std::move(fingerprint);
  return identity;
}

RunQuery Query(int page_size, std::string page_token = "", std::string unit_serial = "") {
  RunQuery query;
  query.page_size = page_size;
  query.page_token = std::move(page_token);
  query.unit_serial = std::move(unit_serial);
  return query;
}

std::vector<engine::ImuSample> ReadAll(RunStore& store, const std::string& id, std::size_t batch) {
  std::vector<engine::ImuSample> samples;
  auto status = store.ReadSamples(id, batch, [&](std::span<const engine::ImuSample> part) {
    samples.insert(samples.end(), part.begin(), part.end());
    return true;
  });
  EXPECT_TRUE(status.ok()) << status;
  return samples;
}

void ExpectSameSamples(const std::vector<engine::ImuSample>& a, const std::vector<engine::ImuSample>& b,
                       bool with_temperature) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].t_s, b[k].t_s) << k;
    ASSERT_EQ(a[k].gyro_rad_s, b[k].gyro_rad_s) << k;
    ASSERT_EQ(a[k].acc_mps2, b[k].acc_mps2) << k;
    ASSERT_EQ(a[k].ref_rpy_rad, b[k].ref_rpy_rad) << k;
    if (with_temperature) {
      ASSERT_EQ(a[k].temp_degc, b[k].temp_degc) << k;
    }
  }
}

TEST_F(RunStoreTest, StoresMetadataAndSamplesBitExactly) {
  const auto run = testing::SyntheticStaticRun(20'000, 50.0, 7);
  auto stored = store_->Create(run, Identity("abc"));
  ASSERT_TRUE(stored.ok()) << stored.status();
  auto got = store_->Get(stored->id);
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->metadata.unit_serial, "INS-2000-0042");
  EXPECT_EQ(got->metadata.unit_type, "INS-2000");
  EXPECT_NEAR(got->metadata.site.latitude_rad, run.metadata.site.latitude_rad, 1e-15);
  EXPECT_EQ(got->metadata.datasheet, run.metadata.datasheet);
  EXPECT_EQ(got->metadata.extra, run.metadata.extra);
  EXPECT_EQ(got->sample_count, 20'000);
  EXPECT_NEAR(got->nominal_interval_s, 0.02, 1e-12);
  EXPECT_NEAR(got->duration_s, 400.0, 1e-9);
  EXPECT_EQ(got->sha256, "abc");
  ExpectSameSamples(ReadAll(*store_, got->id, 3'000), run.samples, true);
}

TEST_F(RunStoreTest, RunWithoutTemperatureRoundTrips) {
  const auto run = testing::SyntheticStaticRun(100, 100.0, 8, /*with_temperature=*/false);
  auto stored = store_->Create(run, Identity("x"));
  ASSERT_TRUE(stored.ok()) << stored.status();
  EXPECT_FALSE(stored->has_temperature);
  ExpectSameSamples(ReadAll(*store_, stored->id, 1'000), run.samples, false);
}

TEST_F(RunStoreTest, SameRequestIdAndFingerprintReturnsTheFirstRun) {
  const auto run = testing::SyntheticStaticRun(10, 50.0, 1);
  const UploadIdentity identity = Identity("s", "req-1", "f");
  auto first = store_->Create(run, identity);
  auto second = store_->Create(run, identity);
  ASSERT_TRUE(first.ok() && second.ok());
  EXPECT_EQ(first->id, second->id);
  auto page = store_->List({});
  ASSERT_TRUE(page.ok());
  EXPECT_EQ(page->runs.size(), 1u);
}

TEST_F(RunStoreTest, SameRequestIdWithOtherContentIsAlreadyExists) {
  const auto run = testing::SyntheticStaticRun(10, 50.0, 1);
  ASSERT_TRUE(store_->Create(run, Identity("s", "req-1", "f")).ok());
  auto reused = store_->Create(run, Identity("t", "req-1", "g"));
  ASSERT_FALSE(reused.ok());
  EXPECT_EQ(reused.status().code(), absl::StatusCode::kAlreadyExists);
  EXPECT_THAT(reused.status().message(), HasSubstr("req-1"));
}

TEST_F(RunStoreTest, ListPagesNewestFirstWithoutGapsOrRepeats) {
  std::vector<std::string> created;
  for (int i = 0; i < 5; ++i) {
    auto run = testing::SyntheticStaticRun(3, 50.0, static_cast<std::uint32_t>(i));
    run.metadata.unit_serial = i % 2 ? "odd" : "even";
    auto stored = store_->Create(run, Identity("s"));
    ASSERT_TRUE(stored.ok()) << stored.status();
    created.insert(created.begin(), stored->id);
  }
  std::vector<std::string> listed;
  RunQuery query = Query(2);
  for (int page_no = 0; page_no < 10; ++page_no) {
    auto page = store_->List(query);
    ASSERT_TRUE(page.ok()) << page.status();
    EXPECT_LE(page->runs.size(), 2u);
    for (const auto& run : page->runs) listed.push_back(run.id);
    if (page->next_page_token.empty()) break;
    query.page_token = page->next_page_token;
  }
  EXPECT_EQ(listed, created);

  auto odd = store_->List(Query(50, "", "odd"));
  ASSERT_TRUE(odd.ok());
  EXPECT_EQ(odd->runs.size(), 2u);

  auto bad = store_->List(Query(50, "not-a-token"));
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(RunStoreTest, DeleteRemovesRunAndSamples) {
  auto stored = store_->Create(testing::SyntheticStaticRun(10, 50.0, 1), Identity("s"));
  ASSERT_TRUE(stored.ok());
  ASSERT_TRUE(store_->Delete(stored->id).ok());
  EXPECT_EQ(store_->Get(stored->id).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(store_->Delete(stored->id).code(), absl::StatusCode::kNotFound);
  auto db = pool().Acquire();
  ASSERT_TRUE(db.ok());
  auto chunks = (*db)->Exec("SELECT count(*) FROM run_sample_chunks");
  ASSERT_TRUE(chunks.ok());
  EXPECT_EQ(chunks->String(0, 0), "0");
}

TEST_F(RunStoreTest, MalformedIdIsInvalidArgumentUnknownIsNotFound) {
  EXPECT_EQ(store_->Get("nope").status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(store_->Get("00000000-0000-0000-0000-000000000000").status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace insdiag::kb
