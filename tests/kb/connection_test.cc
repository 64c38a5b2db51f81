#include <gtest/gtest.h>

#include "insdiag/kb/pg.h"
#include "support/database_fixture.h"

namespace insdiag::kb {
namespace {

class ConnectionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!testing::AdminDatabaseUrl()) GTEST_SKIP() << "INSDIAG_TEST_DATABASE_URL is not set";
    auto database = testing::ScratchDatabase::Create(/*migrated=*/false);
    ASSERT_TRUE(database.ok()) << database.status();
    database_ = std::move(*database);
    auto connection = Connection::Open(database_->url());
    ASSERT_TRUE(connection.ok()) << connection.status();
    db_ = std::make_unique<Connection>(std::move(*connection));
  }
  std::unique_ptr<testing::ScratchDatabase> database_;
  std::unique_ptr<Connection> db_;
};

// A database named by a user (the server's --database) may hold quotes,
// spaces and SQL: quoted, it names exactly one object and runs nothing else.
TEST_F(ConnectionTest, AQuotedIdentifierNamesExactlyTheObjectItSpells) {
  const std::string hostile = "bench \"A\"; DROP TABLE kept; --";
  ASSERT_TRUE(db_->ExecScript("CREATE TABLE kept (x int)").ok());
  auto quoted = db_->QuoteIdentifier(hostile);
  ASSERT_TRUE(quoted.ok()) << quoted.status();
  ASSERT_TRUE(db_->ExecScript("CREATE TABLE " + *quoted + " (y int)").ok());

  auto names =
      db_->Exec("SELECT count(*) FROM pg_class WHERE relname = ANY($1::text[]) AND relkind = 'r'",
                {Param::TextArray({hostile, "kept"})});
  ASSERT_TRUE(names.ok()) << names.status();
  EXPECT_EQ(names->String(0, 0), "2");
}

}  // namespace
}  // namespace insdiag::kb
