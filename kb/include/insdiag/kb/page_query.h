// One page of a keyset-paginated list, as the stores take it.
#pragma once

#include <string>

namespace insdiag::kb {

struct PageQuery {
  int page_size = 50;
  std::string page_token;  // from the previous page; empty for the first
};

}  // namespace insdiag::kb
