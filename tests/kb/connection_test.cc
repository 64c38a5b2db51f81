#include <gtest/gtest.h>

#include "insdiag/kb/pg.h"
#include "support/database_fixture.h"

namespace insdiag::kb {
namespace {

using ConnectionTest = testing::DatabaseTest;

// A database named by a user (the server's --database) may hold quotes,
// spaces and SQL: quoted, it names exactly one object and runs nothing else.
TEST_F(ConnectionTest, AQuotedIdentifierNamesExactlyTheObjectItSpells) {
  auto db = pool().Acquire();
  ASSERT_TRUE(db.ok()) << db.status();
  const std::string hostile = "bench \"A\"; DROP TABLE kept; --";
  ASSERT_TRUE((*db)->ExecScript("CREATE TABLE kept (x int)").ok());
  auto quoted = (*db)->QuoteIdentifier(hostile);
  ASSERT_TRUE(quoted.ok()) << quoted.status();
  ASSERT_TRUE((*db)->ExecScript("CREATE TABLE " + *quoted + " (y int)").ok());

  auto names = (*db)->Exec("SELECT count(*) FROM pg_class WHERE relname = ANY($1::text[]) AND relkind = 'r'",
                           {Param::TextArray({hostile, "kept"})});
  ASSERT_TRUE(names.ok()) << names.status();
  EXPECT_EQ(names->String(0, 0), "2");
}

}  // namespace
}  // namespace insdiag::kb
