// The paging helpers (src/core/huge_pages.hpp): release_read_pages hands back the whole pages
// of a text's read part, and only those.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "core/huge_pages.hpp"

namespace nonplanar {
namespace {

TEST(ReleaseReadPages, TheWholePagesReadGoAndNothingElse) {
  constexpr std::size_t kPage = 4096;
  std::string s(20 * kPage + 123, 'x');
  const auto base = reinterpret_cast<std::uintptr_t>(s.data());
  const std::size_t into_page = (kPage - base % kPage) % kPage;  // bytes before the first page
  std::size_t released = 0;
  // Less than a whole page read: nothing goes.
  release_read_pages(s, into_page + kPage - 1, released);
  EXPECT_EQ(released, 0u);
  EXPECT_EQ(s.find('\0'), std::string::npos);
  // Three pages and a bit: those three read as zeros after, the rest as written.
  const std::size_t upto = into_page + 3 * kPage + 100;
  release_read_pages(s, upto, released);
  EXPECT_EQ(released, into_page + 3 * kPage);
  EXPECT_EQ(s.find('\0'), into_page);
  EXPECT_EQ(s.find_first_not_of('\0', into_page), into_page + 3 * kPage);
  EXPECT_EQ(s.find('\0', into_page + 3 * kPage), std::string::npos);
  // On from there; past the end only up to the last whole page.
  release_read_pages(s, s.size() + 5000, released);
  const std::size_t last = (base + s.size()) / kPage * kPage - base;
  EXPECT_EQ(released, last);
  EXPECT_EQ(s.find_first_not_of('\0', into_page), last);
  // Asked for less than already released: nothing moves.
  release_read_pages(s, 10, released);
  EXPECT_EQ(released, last);
}

}  // namespace
}  // namespace nonplanar
