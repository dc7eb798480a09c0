// Power loss everywhere (issue #20, part 8): the update is cut at every word it programs, with
// the word being programmed left partly programmed and a page being erased left partly erased,
// in random states from a seeded PRNG; after each cut the tag boots, and a second update (the
// PC's retry, the recovery) is cut again at every one of its words, and the tag boots again.
// After every boot the invariants of docs/calibration-blob.md section 6 are asserted:
//   I1 metro_fw_load succeeds;
//   I2 the tag runs exactly the calibration active before the update or exactly the new one
//      (slot, seq, crc32, flags and both sensors' constants equal those of a clean boot of
//      that state: never defaults, never a mix);
//   I3 it runs the new one exactly when the commit word holds the whole magic, which the model
//      decides (the cut fell after the commit word, or the partial programming of the commit
//      word happened to clear every bit the magic needs);
//   I4 the slot active before the update is byte for byte what it was;
//   I5 the tag takes a clean update afterwards.
#include <catch2/catch.hpp>
#include <cstring>
#include <random>

#include "metro_fw/blob.h"
#include "metro_fw/update.h"
#include "test_support.hpp"

using fwtest::Build;
using fwtest::StandardBlob;

namespace {

// Random 32-bit patterns of varied density: none, every bit, sparse, half, dense.
uint32_t RandomMask(std::mt19937_64& rng) {
  const uint64_t r = rng();
  const uint32_t a = static_cast<uint32_t>(r), b = static_cast<uint32_t>(r >> 32);
  switch (rng() % 5) {
    case 0:
      return 0u;
    case 1:
      return 0xFFFFFFFFu;
    case 2:
      return a & b;
    case 3:
      return a;
    default:
      return a | b;
  }
}

// Both slot pages with nRF51 semantics and power loss at word granularity. Every erase is one
// step, every word a write programs is one step. During step `cut_step` the power fails: a
// word being programmed clears a random subset of the bits it should clear; a page being
// erased sets a random subset of its zero bits (per word, random density), i.e. a partly
// erased page in a random state. From then on every callback, reads included, fails and
// changes nothing, until Reboot().
class PowerFlash {
 public:
  PowerFlash() : mem_(2 * METRO_FW_PAGE_SIZE, 0xFF) {}

  metro_fw_flash Interface() {
    metro_fw_flash f{};
    f.read = &PowerFlash::Read;
    f.erase_page = &PowerFlash::Erase;
    f.write = &PowerFlash::Write;
    f.ctx = this;
    f.slot_addr[0] = METRO_FW_SLOT_A_ADDR;
    f.slot_addr[1] = METRO_FW_SLOT_B_ADDR;
    return f;
  }
  void Program(int slot, const std::vector<uint8_t>& bytes) {
    std::memcpy(Slot(slot), bytes.data(), bytes.size());
  }
  uint8_t* Slot(int i) { return mem_.data() + i * METRO_FW_PAGE_SIZE; }
  std::vector<uint8_t> Page(int i) { return {Slot(i), Slot(i) + METRO_FW_PAGE_SIZE}; }
  uint32_t Word(int slot, uint32_t off) {
    const uint8_t* p = Slot(slot) + off;
    return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
  }
  // A partly erased page in a random state over what it held.
  void PartlyErase(int slot, std::mt19937_64& rng) { PartlyErase(Slot(slot), rng); }

  void Arm(long cut_step, std::mt19937_64* rng) {
    steps = 0;
    cut_step_ = cut_step;
    rng_ = rng;
  }
  void Reboot() {
    dead_ = false;
    cut_step_ = -1;
  }

  long steps = 0;    // steps begun since Arm()
  long cut_at = -1;  // the step that was cut, -1 if none

 private:
  static void PartlyErase(uint8_t* page, std::mt19937_64& rng) {
    for (uint32_t w = 0; w < METRO_FW_PAGE_SIZE; w += 4) {
      const uint32_t m = RandomMask(rng);
      for (int i = 0; i < 4; ++i) page[w + i] |= static_cast<uint8_t>(m >> (8 * i));
    }
  }
  // true when step begins with power; sets *cut when it is the step the power fails in.
  bool Step(bool* cut) {
    *cut = false;
    if (dead_) return false;
    if (steps++ == cut_step_) {
      *cut = true;
      dead_ = true;
      cut_at = cut_step_;
    }
    return true;
  }
  bool InRange(uint32_t addr, uint32_t len) const {
    return addr >= METRO_FW_SLOT_A_ADDR && addr - METRO_FW_SLOT_A_ADDR + len <= mem_.size();
  }
  static int Read(void* ctx, uint32_t addr, uint8_t* dst, uint32_t len) {
    auto* self = static_cast<PowerFlash*>(ctx);
    if (self->dead_ || !self->InRange(addr, len)) return -1;
    std::memcpy(dst, self->mem_.data() + (addr - METRO_FW_SLOT_A_ADDR), len);
    return 0;
  }
  static int Erase(void* ctx, uint32_t addr) {
    auto* self = static_cast<PowerFlash*>(ctx);
    if (addr % METRO_FW_PAGE_SIZE != 0 || !self->InRange(addr, METRO_FW_PAGE_SIZE)) return -1;
    bool cut;
    if (!self->Step(&cut)) return -1;
    uint8_t* p = self->mem_.data() + (addr - METRO_FW_SLOT_A_ADDR);
    if (cut) {
      PartlyErase(p, *self->rng_);
      return -1;
    }
    std::memset(p, 0xFF, METRO_FW_PAGE_SIZE);
    return 0;
  }
  static int Write(void* ctx, uint32_t addr, const uint8_t* src, uint32_t len) {
    auto* self = static_cast<PowerFlash*>(ctx);
    if (addr % 4 != 0 || len % 4 != 0 || !self->InRange(addr, len)) return -1;
    for (uint32_t w = 0; w < len; w += 4) {
      bool cut;
      if (!self->Step(&cut)) return -1;
      uint8_t* p = self->mem_.data() + (addr - METRO_FW_SLOT_A_ADDR) + w;
      const uint32_t keep = cut ? ~RandomMask(*self->rng_) : 0u;  // bits that stay as they were
      for (int i = 0; i < 4; ++i) {
        p[i] &= static_cast<uint8_t>(src[w + i] | (keep >> (8 * i)));
      }
      if (cut) return -1;
    }
    return 0;
  }

  std::vector<uint8_t> mem_;
  bool dead_ = false;
  long cut_step_ = -1;
  std::mt19937_64* rng_ = nullptr;
};

// Everything a boot publishes that decides what the tag runs.
struct Boot {
  int slot;
  uint32_t seq, crc32, flags;
  metro_fw_sensor_cal accel, gyro;
};

Boot DoBoot(PowerFlash& flash) {
  metro_fw_flash f = flash.Interface();
  metro_fw_config cfg = fwtest::Config();
  metro_fw_calibration cal;
  std::memset(&cal, 0xA5, sizeof(cal));
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);  // I1
  return {cal.slot, cal.seq, cal.crc32, cal.flags, cal.accel, cal.gyro};
}

bool Same(const Boot& a, const Boot& b) {
  return a.slot == b.slot && a.seq == b.seq && a.crc32 == b.crc32 && a.flags == b.flags &&
         std::memcmp(&a.accel, &b.accel, sizeof(a.accel)) == 0 &&
         std::memcmp(&a.gyro, &b.gyro, sizeof(a.gyro)) == 0;
}

// The blob the tests write: the standard one with other constants per seq, so the old and the
// new calibration differ in their sensors too (a mix would show).
std::vector<uint8_t> BlobOf(uint32_t seq) {
  fwtest::Blob b = StandardBlob(seq);
  auto accel = fwtest::GoodAccel();
  accel.b0[0] = static_cast<float>(seq % 1000);
  b.sections[1].body = fwtest::SensorBody(accel);
  return Build(b);
}

// What the tag boots when `slot` holds `blob` and the other slot `other_page` (clean boot of a
// state, the reference for I2).
Boot Reference(int slot, const std::vector<uint8_t>& blob, const std::vector<uint8_t>& other_page) {
  PowerFlash f;
  f.Program(1 - slot, other_page);
  std::vector<uint8_t> page(METRO_FW_PAGE_SIZE, 0xFF);
  std::copy(blob.begin(), blob.end(), page.begin());
  f.Program(slot, page);
  return DoBoot(f);
}

// Steps of one update of a blob of total_len bytes: erase, the body's words, the commit word.
long StepsOfUpdate(size_t total_len) { return 1 + static_cast<long>(total_len - 4) / 4 + 1; }

int RunUpdate(PowerFlash& flash, const std::vector<uint8_t>& blob, int* slot = nullptr) {
  metro_fw_flash f = flash.Interface();
  return metro_fw_update(&f, fwtest::kDeviceId, blob.data(), static_cast<uint32_t>(blob.size()),
                         slot);
}

// Initial flash states before the update: slot A and B pages.
struct Initial {
  const char* name;
  std::vector<uint8_t> page[2];
};

std::vector<uint8_t> PageOf(const std::vector<uint8_t>& blob) {
  std::vector<uint8_t> p(METRO_FW_PAGE_SIZE, 0xFF);
  std::copy(blob.begin(), blob.end(), p.begin());
  return p;
}

std::vector<Initial> InitialStates() {
  std::mt19937_64 rng(20);
  const std::vector<uint8_t> erased(METRO_FW_PAGE_SIZE, 0xFF);
  std::vector<Initial> v;
  v.push_back({"A valid, B erased", {PageOf(BlobOf(5)), erased}});
  v.push_back({"A valid, B older", {PageOf(BlobOf(5)), PageOf(BlobOf(4))}});
  v.push_back({"A older, B valid", {PageOf(BlobOf(4)), PageOf(BlobOf(5))}});
  {
    // B partly erased over an older blob, in a random state
    PowerFlash f;
    f.Program(1, PageOf(BlobOf(4)));
    f.PartlyErase(1, rng);
    v.push_back({"A valid, B partly erased", {PageOf(BlobOf(5)), f.Page(1)}});
  }
  {
    // B torn by an earlier cut: most of a body, a partly programmed commit word
    auto torn = PageOf(BlobOf(9));
    for (size_t i = 300; i < torn.size(); ++i) torn[i] = 0xFF;
    torn[0] = 0xFF;
    torn[2] = 0xFF;
    v.push_back({"A valid, B torn", {PageOf(BlobOf(5)), torn}});
  }
  v.push_back({"both erased", {erased, erased}});
  return v;
}

// One cut update from the state in `flash`, then a boot; checks I2-I4 against `before` (the
// boot of the state before) and `blob` (the update's). Returns the boot after the cut.
Boot CutAndBoot(PowerFlash& flash, const Boot& before, const std::vector<uint8_t>& blob, long cut,
                std::mt19937_64& rng) {
  const int target = before.slot == 0 ? 1 : 0;
  const std::vector<uint8_t> kept = flash.Page(1 - target);
  flash.Arm(cut, &rng);
  flash.cut_at = -1;
  const int rc = RunUpdate(flash, blob);
  const bool was_cut = flash.cut_at >= 0;
  flash.Reboot();
  const Boot after = DoBoot(flash);
  // I3: the model decides which calibration must be running.
  const long n = StepsOfUpdate(blob.size());
  const bool commit_whole = flash.Word(target, 0) == METRO_FW_MAGIC;
  const bool expect_is_new = !was_cut || (cut == n - 1 && commit_whole);
  INFO("cut at step " << cut << " of " << n << ", update result " << rc);
  if (!was_cut) CHECK(rc == METRO_FW_OK);
  if (expect_is_new) {
    CHECK(Same(after, Reference(target, blob, kept)));  // I2
    CHECK(after.seq == fwtest::Get32(blob, 12));
  } else {
    CHECK(Same(after, before));  // I2
  }
  if (before.slot != METRO_FW_SLOT_NONE) {
    CHECK(after.slot != METRO_FW_SLOT_NONE);
    CHECK(after.accel.status == METRO_FW_SENSOR_OK);
    CHECK(after.gyro.status == METRO_FW_SENSOR_OK);
  }
  CHECK(flash.Page(1 - target) == kept);  // I4
  return after;
}

}  // namespace

TEST_CASE("A power cut at every word of an update, in random partial states, boots old or new",
          "[fw][update][power]") {
  const auto blob = BlobOf(6);
  const long n = StepsOfUpdate(blob.size());
  REQUIRE(n == 136);  // erase, 134 body words, the commit word
  long news = 0, olds = 0, partial_commits = 0;
  for (const auto& init : InitialStates()) {
    for (uint64_t seed = 0; seed < 8; ++seed) {
      std::mt19937_64 rng(seed * 7919 + 1);
      for (long cut = 0; cut <= n; ++cut) {  // n: no cut
        PowerFlash flash;
        flash.Program(0, init.page[0]);
        flash.Program(1, init.page[1]);
        const Boot before = DoBoot(flash);
        INFO(init.name << ", seed " << seed);
        const Boot after = CutAndBoot(flash, before, blob, cut, rng);
        (after.seq == 6u ? news : olds) += 1;
        if (cut == n - 1 && after.seq == 6u) ++partial_commits;
        // I5: the tag takes the next update.
        REQUIRE(RunUpdate(flash, BlobOf(7)) == METRO_FW_OK);
        CHECK(DoBoot(flash).seq == 7u);
      }
    }
  }
  // Every cut before the commit word keeps the old calibration; after it, the new one; the
  // random commit words cover both outcomes.
  CHECK(olds >= 6 * 8 * (n - 1));
  CHECK(partial_commits > 0);
  CHECK(news - partial_commits == 6 * 8);
}

TEST_CASE("A second cut during the recovery update after a first cut boots a valid state",
          "[fw][update][power]") {
  // The recovery is what the PC does after the link comes back: GET_INFO, then a push. Variant
  // 0 retries the same blob (seq 6: `calibrate push --seq 6`, or the active seq + 1 when the
  // old calibration survived); variant 1 pushes other constants with the active seq + 2. The
  // recovery update is cut at every one of its steps.
  const auto blob = BlobOf(6);
  const long n = StepsOfUpdate(blob.size());
  const auto inits = InitialStates();
  long recoveries = 0;
  for (size_t which : {size_t{0}, size_t{2}, size_t{4}}) {
    const Initial& init = inits[which];
    std::mt19937_64 rng(which + 100);
    for (long cut1 = 0; cut1 < n; ++cut1) {
      PowerFlash after_first;
      after_first.Program(0, init.page[0]);
      after_first.Program(1, init.page[1]);
      const Boot before = DoBoot(after_first);
      INFO(init.name << ", first cut " << cut1);
      const Boot first = CutAndBoot(after_first, before, blob, cut1, rng);
      for (int variant = 0; variant < 2; ++variant) {
        for (long cut2 = 0; cut2 <= n; ++cut2) {
          PowerFlash flash = after_first;  // the state the first cut left
          INFO("variant " << variant << ", second cut " << cut2);
          const auto retry = variant == 0 ? blob : BlobOf(first.seq + 2);
          if (variant == 0 && first.seq == 6u) {
            // Already live: the retry is refused before any flash operation.
            flash.Arm(-1, &rng);
            CHECK(RunUpdate(flash, retry) == METRO_FW_E_STALE_SEQ);
            CHECK(flash.steps == 0);
            continue;
          }
          ++recoveries;
          CutAndBoot(flash, first, retry, cut2, rng);
          REQUIRE(RunUpdate(flash, BlobOf(100)) == METRO_FW_OK);  // I5
        }
      }
    }
  }
  CHECK(recoveries >= 3 * n * (n + 1));
}

TEST_CASE("Power lost after the commit word, during the read-back: live, unverified",
          "[fw][update][power]") {
  // The flash dies once the commit word is programmed (step 136 of 136 done): the update's
  // read-back through the validator fails, and the result still says the new calibration is
  // live, as the next boot confirms.
  struct Ctx {
    PowerFlash* flash;
    metro_fw_flash inner;
  };
  const auto blob = BlobOf(6);
  REQUIRE(StepsOfUpdate(blob.size()) == 136);
  PowerFlash flash;
  flash.Program(0, PageOf(BlobOf(5)));
  std::mt19937_64 rng(1);
  flash.Arm(-1, &rng);
  Ctx ctx{&flash, flash.Interface()};
  metro_fw_flash dying = ctx.inner;
  dying.ctx = &ctx;
  dying.read = [](void* c, uint32_t addr, uint8_t* dst, uint32_t len) {
    auto* x = static_cast<Ctx*>(c);
    if (x->flash->steps >= 136) return -1;
    return x->inner.read(x->inner.ctx, addr, dst, len);
  };
  dying.erase_page = [](void* c, uint32_t addr) {
    auto* x = static_cast<Ctx*>(c);
    return x->inner.erase_page(x->inner.ctx, addr);
  };
  dying.write = [](void* c, uint32_t addr, const uint8_t* src, uint32_t len) {
    auto* x = static_cast<Ctx*>(c);
    return x->inner.write(x->inner.ctx, addr, src, len);
  };
  int slot = -3;
  CHECK(metro_fw_update(&dying, fwtest::kDeviceId, blob.data(), static_cast<uint32_t>(blob.size()),
                        &slot) == METRO_FW_LIVE_UNVERIFIED);
  CHECK(slot == 1);
  const Boot after = DoBoot(flash);
  CHECK(after.slot == 1);
  CHECK(after.seq == 6u);
}
