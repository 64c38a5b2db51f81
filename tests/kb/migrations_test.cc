#include "insdiag/kb/migrations.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "support/database_fixture.h"
#include "support/subprocess.h"

namespace insdiag::kb {
namespace {

using ::testing::HasSubstr;

class MigrationsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!testing::AdminDatabaseUrl()) GTEST_SKIP() << "INSDIAG_TEST_DATABASE_URL is not set";
    auto database = testing::ScratchDatabase::Create(/*migrated=*/false);
    ASSERT_TRUE(database.ok()) << database.status();
    database_ = std::move(*database);
  }
  Connection Connect() {
    auto connection = Connection::Open(database_->url());
    EXPECT_TRUE(connection.ok()) << connection.status();
    return std::move(*connection);
  }
  std::unique_ptr<testing::ScratchDatabase> database_;
};

std::vector<Migration> TwoMigrations() {
  return {{1, "0001_a.sql", "CREATE TABLE a (x int);"},
          {2, "0002_b.sql", "CREATE TABLE b (y int); INSERT INTO a VALUES (1);"}};
}

TEST_F(MigrationsTest, AppliesInOrderOnceAndRecordsChecksums) {
  auto db = Connect();
  auto first = ApplyMigrations(db, TwoMigrations());
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->applied, 2);
  auto again = ApplyMigrations(db, TwoMigrations());
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->applied, 0);
  EXPECT_EQ(again->already_applied, 2);

  auto rows = db.Exec("SELECT count(*) FROM a");
  ASSERT_TRUE(rows.ok());
  EXPECT_EQ(rows->String(0, 0), "1") << "0002 ran once, after 0001";
  auto recorded = db.Exec("SELECT name, sha256 FROM schema_migrations ORDER BY version");
  ASSERT_TRUE(recorded.ok());
  ASSERT_EQ(recorded->rows(), 2);
  EXPECT_EQ(recorded->String(1, 0), "0002_b.sql");
  EXPECT_EQ(recorded->String(1, 1), MigrationChecksum(TwoMigrations()[1]));
}

TEST_F(MigrationsTest, ChangedAppliedMigrationIsRefusedNamingTheFile) {
  auto db = Connect();
  ASSERT_TRUE(ApplyMigrations(db, TwoMigrations()).ok());
  auto edited = TwoMigrations();
  edited[0].sql = "CREATE TABLE a (x bigint);";
  auto refused = ApplyMigrations(db, edited);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(refused.status().message(), HasSubstr("0001_a.sql has changed"));
}

TEST_F(MigrationsTest, FailingMigrationRollsBackAndIsNotRecorded) {
  auto db = Connect();
  std::vector<Migration> broken = {{1, "0001_a.sql", "CREATE TABLE a (x int); SELECT no_such_function();"}};
  auto failed = ApplyMigrations(db, broken);
  ASSERT_FALSE(failed.ok());
  EXPECT_THAT(failed.status().message(), HasSubstr("0001_a.sql"));
  auto table = db.Exec("SELECT to_regclass('a') IS NULL");
  ASSERT_TRUE(table.ok());
  EXPECT_TRUE(table->Bool(0, 0)) << "the half-applied migration must be rolled back";
  auto recorded = db.Exec("SELECT count(*) FROM schema_migrations");
  ASSERT_TRUE(recorded.ok());
  EXPECT_EQ(recorded->String(0, 0), "0");
}

TEST_F(MigrationsTest, ConcurrentRunnersApplyEachMigrationOnce) {
  std::vector<absl::StatusOr<MigrationReport>> reports(4, absl::UnknownError("not run"));
  std::vector<std::thread> runners;
  for (auto& report : reports) {
    runners.emplace_back([&] {
      auto db = Connection::Open(database_->url());
      report = db.ok() ? ApplyMigrations(*db, TwoMigrations()) : db.status();
    });
  }
  for (auto& runner : runners) runner.join();
  int applied = 0;
  for (const auto& report : reports) {
    ASSERT_TRUE(report.ok()) << report.status();
    applied += report->applied;
  }
  EXPECT_EQ(applied, 2);
}

TEST_F(MigrationsTest, DatabaseNewerThanTheServerIsRefused) {
  auto db = Connect();
  ASSERT_TRUE(ApplyMigrations(db, TwoMigrations()).ok());
  auto older = TwoMigrations();
  older.pop_back();
  auto refused = ApplyMigrations(db, older);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), HasSubstr("0002_b.sql"));
}

TEST_F(MigrationsTest, EmbeddedMigrationsMatchTheFilesAndApply) {
  auto from_files = LoadMigrationsFromDirectory(INSDIAG_SOURCE_DIR "/migrations");
  ASSERT_TRUE(from_files.ok()) << from_files.status();
  const auto embedded = EmbeddedMigrations();
  ASSERT_EQ(embedded.size(), from_files->size());
  for (std::size_t i = 0; i < embedded.size(); ++i) {
    EXPECT_EQ(embedded[i].name, (*from_files)[i].name);
    EXPECT_EQ(MigrationChecksum(embedded[i]), MigrationChecksum((*from_files)[i])) << embedded[i].name;
  }
  auto db = Connect();
  auto applied = ApplyMigrations(db, embedded);
  ASSERT_TRUE(applied.ok()) << applied.status();
  EXPECT_EQ(applied->applied, static_cast<int>(embedded.size()));
}

TEST(MigrationFiles, BadlyNamedFileIsRefused) {
  const auto dir = testing::MakeTempDir("insdiag-migrations");
  std::ofstream(dir / "1_runs.sql") << "SELECT 1;";
  auto loaded = LoadMigrationsFromDirectory(dir);
  std::filesystem::remove_all(dir);
  ASSERT_FALSE(loaded.ok());
  EXPECT_THAT(loaded.status().message(), HasSubstr("1_runs.sql"));
}

}  // namespace
}  // namespace insdiag::kb
