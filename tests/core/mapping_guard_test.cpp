// A file that shrinks under a read-only mapping (core/mapping_guard.hpp): the pages beyond
// the new end read as zeros instead of raising SIGBUS, and the change is reported.
#include "core/mapping_guard.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <string>

#include "support/temp_file.hpp"

namespace metro {
namespace {

TEST_CASE("A file truncated under its mapping reads as zeros and is reported", "[core][file]") {
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  const size_t size = 5 * page;
  testing::TempFile file(std::string(size, 'x'), ".bin");
  const int fd = ::open(file.path().c_str(), O_RDONLY);
  REQUIRE(fd >= 0);
  struct stat st {};
  REQUIRE(::fstat(fd, &st) == 0);
  void* map = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
  REQUIRE(map != MAP_FAILED);
  const volatile char* bytes = static_cast<const char*>(map);
  {
    internal::MappingGuard guard(map, size);
    REQUIRE(guard.Guarded());
    CHECK(bytes[2 * page] == 'x');
    CHECK_FALSE(guard.Shrunk());
    CHECK(internal::ChangedWhileRead(fd, internal::IdentityOf(st), guard.Shrunk()).empty());

    // Another writer cuts the file to one page and a half.
    REQUIRE(::truncate(file.path().c_str(), static_cast<off_t>(page + page / 2)) == 0);
    // Without the guard the next read would end the process (SIGBUS).
    CHECK(bytes[3 * page + 7] == 0);
    CHECK(bytes[size - 1] == 0);
    CHECK(guard.Shrunk());
    CHECK(bytes[page / 2] == 'x');  // The first page is still the file's.
    const std::string why = internal::ChangedWhileRead(fd, internal::IdentityOf(st), true);
    CHECK(why.find("the file changed while metro read it (" + std::to_string(size) +
                   " bytes when opened, " + std::to_string(page + page / 2) +
                   " bytes now; it shrank under the reader)") == 0);
  }
  ::munmap(map, size);
  ::close(fd);
}

TEST_CASE("A file rewritten to the same size is a change too", "[core][file]") {
  testing::TempFile file("t_s,gx_dps\n0,1\n", ".csv");
  const int fd = ::open(file.path().c_str(), O_RDONLY);
  REQUIRE(fd >= 0);
  struct stat st {};
  REQUIRE(::fstat(fd, &st) == 0);
  // A modification time one second later, as another writer leaves it.
  struct timespec times[2] = {st.st_atim, st.st_mtim};
  times[1].tv_sec += 1;
  REQUIRE(::utimensat(AT_FDCWD, file.path().c_str(), times, 0) == 0);
  const std::string why = internal::ChangedWhileRead(fd, internal::IdentityOf(st), false);
  CHECK(why.find("the file changed while metro read it (15 bytes when opened, 15 bytes now)") == 0);
  ::close(fd);
}

}  // namespace
}  // namespace metro
