// The power-fail-safe update: flash errors, a power cut at every step, 10^4 updates.
#include "metro_fw/update.h"

#include <catch2/catch.hpp>

#include "test_support.hpp"

using fwtest::Build;
using fwtest::FakeFlash;
using fwtest::StandardBlob;

namespace {

int Update(FakeFlash& flash, const std::vector<uint8_t>& blob, int* slot = nullptr) {
  metro_fw_flash f = flash.Interface();
  return metro_fw_update(&f, fwtest::kDeviceId, blob.data(), static_cast<uint32_t>(blob.size()),
                         slot);
}

metro_fw_calibration Load(FakeFlash& flash) {
  metro_fw_flash f = flash.Interface();
  metro_fw_config cfg = fwtest::Config();
  metro_fw_calibration cal{};
  REQUIRE(metro_fw_load(&f, &cfg, &cal) == METRO_FW_OK);
  return cal;
}

// Number of erase/write operations of one clean update.
int OpsOfCleanUpdate() {
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  REQUIRE(Update(flash, Build(StandardBlob(6))) == METRO_FW_OK);
  return flash.ops;
}

}  // namespace

TEST_CASE("An update into empty flash writes slot A and the next one slot B", "[fw][update]") {
  FakeFlash flash;
  int slot = -5;
  REQUIRE(Update(flash, Build(StandardBlob(1)), &slot) == METRO_FW_OK);
  CHECK(slot == 0);
  REQUIRE(Update(flash, Build(StandardBlob(2)), &slot) == METRO_FW_OK);
  CHECK(slot == 1);
  const auto cal = Load(flash);
  CHECK(cal.slot == 1);
  CHECK(cal.seq == 2u);
  // Slot A still holds the previous calibration, byte for byte.
  const auto first = Build(StandardBlob(1));
  CHECK(std::equal(first.begin(), first.end(), flash.Slot(0)));
  // Bytes after total_len stay erased.
  CHECK(flash.Slot(1)[540] == 0xFF);
  CHECK(flash.Slot(1)[1023] == 0xFF);
}

TEST_CASE("An update with a seq not above the active one is refused", "[fw][update]") {
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(7)));
  CHECK(Update(flash, Build(StandardBlob(7))) == METRO_FW_E_STALE_SEQ);
  CHECK(Update(flash, Build(StandardBlob(3))) == METRO_FW_E_STALE_SEQ);
  CHECK(flash.ops == 0);  // nothing was erased
  FakeFlash full;
  full.Program(METRO_FW_SLOT_B_ADDR, Build(StandardBlob(METRO_FW_SEQ_MAX)));
  CHECK(Update(full, Build(StandardBlob(1))) == METRO_FW_E_STALE_SEQ);
}

TEST_CASE("An invalid blob is refused before flash is touched", "[fw][update]") {
  FakeFlash flash;
  auto foreign = StandardBlob(2);
  foreign.device_id[0] = 1;
  CHECK(Update(flash, Build(foreign)) == METRO_FW_E_FOREIGN);
  auto bad = Build(StandardBlob(2));
  bad[100] ^= 1;
  CHECK(Update(flash, bad) == METRO_FW_E_CRC);
  CHECK(flash.ops == 0);
}

TEST_CASE("Flash errors on erase and on write are reported and keep the old calibration",
          "[fw][update]") {
  const int n = OpsOfCleanUpdate();
  REQUIRE(n == 3);  // erase, write body, write magic
  for (int op = 0; op < n; ++op) {
    FakeFlash flash;
    flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
    flash.fail_at = op;
    INFO("failing operation " << op);
    CHECK(Update(flash, Build(StandardBlob(6))) == METRO_FW_E_FLASH);
    const auto cal = Load(flash);
    CHECK(cal.slot == 0);
    CHECK(cal.seq == 5u);
  }
}

TEST_CASE("A read-back difference stops the update before the commit", "[fw][update]") {
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  flash.stuck_byte = 300;  // this byte of the target page does not program
  CHECK(Update(flash, Build(StandardBlob(6))) == METRO_FW_E_VERIFY);
  CHECK(flash.Slot(1)[0] == 0xFF);  // the magic word was never written
  CHECK(Load(flash).seq == 5u);
}

TEST_CASE("A power cut at every step leaves the old or the new calibration", "[fw][update]") {
  const int n = OpsOfCleanUpdate();
  for (auto tear :
       {FakeFlash::Tear::kNothing, FakeFlash::Tear::kFirstHalf, FakeFlash::Tear::kSecondHalf}) {
    for (int initial = 0; initial < 3; ++initial) {
      for (int cut = 0; cut <= n; ++cut) {
        FakeFlash flash;
        // 0: only A valid; 1: A newer than a valid B; 2: B newer than a valid A.
        if (initial == 0) flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
        if (initial == 1) {
          flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
          flash.Program(METRO_FW_SLOT_B_ADDR, Build(StandardBlob(4)));
        }
        if (initial == 2) {
          flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(4)));
          flash.Program(METRO_FW_SLOT_B_ADDR, Build(StandardBlob(5)));
        }
        flash.cut_at = cut;  // cut == n: no cut, the update completes
        flash.tear = tear;
        const int rc = Update(flash, Build(StandardBlob(6)));
        flash.Revive();  // reboot
        const auto cal = Load(flash);
        INFO("tear " << static_cast<int>(tear) << " initial " << initial << " cut " << cut);
        CHECK(cal.slot != METRO_FW_SLOT_NONE);
        CHECK((cal.seq == 5u || cal.seq == 6u));
        if (rc == METRO_FW_OK) CHECK(cal.seq == 6u);
        if (cut == n) CHECK(rc == METRO_FW_OK);
        CHECK(cal.accel.status == METRO_FW_SENSOR_OK);
        // After the reboot an update completes.
        REQUIRE(Update(flash, Build(StandardBlob(7))) == METRO_FW_OK);
        CHECK(Load(flash).seq == 7u);
      }
    }
  }
}

TEST_CASE("Ten thousand updates alternate between the slots and seq only grows",
          "[fw][update][slow]") {
  FakeFlash flash;
  int slot = -1;
  for (uint32_t seq = 1; seq <= 10000; ++seq) {
    REQUIRE(Update(flash, Build(StandardBlob(seq)), &slot) == METRO_FW_OK);
    REQUIRE(slot == static_cast<int>((seq - 1) % 2));
  }
  const auto cal = Load(flash);
  CHECK(cal.seq == 10000u);
  CHECK(cal.slot == 1);
  CHECK(flash.ops == 3 * 10000);
}

TEST_CASE("Update refuses NULL arguments", "[fw][update]") {
  FakeFlash flash;
  metro_fw_flash f = flash.Interface();
  const auto blob = Build(StandardBlob(1));
  CHECK(metro_fw_update(nullptr, fwtest::kDeviceId, blob.data(), 540, nullptr) == METRO_FW_E_ARG);
  CHECK(metro_fw_update(&f, nullptr, blob.data(), 540, nullptr) == METRO_FW_E_ARG);
  CHECK(metro_fw_update(&f, fwtest::kDeviceId, nullptr, 540, nullptr) == METRO_FW_E_ARG);
}

TEST_CASE("After the commit word a failed read-back still says the new calibration is live",
          "[fw][update]") {
  // Operations: 0 erase, 1 body, 2 commit word. Reads fail from the commit on, so the final
  // read-back through the validator cannot read the slot; the commit happened.
  FakeFlash flash;
  flash.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  flash.reads_fail_from = 3;
  int slot = -5;
  CHECK(Update(flash, Build(StandardBlob(6)), &slot) == METRO_FW_LIVE_UNVERIFIED);
  CHECK(slot == 1);
  flash.reads_fail_from = -1;  // reboot
  const auto cal = Load(flash);
  CHECK(cal.slot == 1);
  CHECK(cal.seq == 6u);
  // Reads failing before the commit: the body cannot be verified, nothing is committed.
  FakeFlash early;
  early.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  early.reads_fail_from = 2;
  CHECK(Update(early, Build(StandardBlob(6)), &slot) == METRO_FW_E_FLASH);
  CHECK(slot == METRO_FW_SLOT_NONE);
  early.reads_fail_from = -1;
  CHECK(Load(early).seq == 5u);
  CHECK(early.Slot(1)[0] == 0xFF);
}

TEST_CASE("A commit write that reports an error is judged by the read-back", "[fw][update]") {
  // The word landed although the callback said no: the slot reads back valid, so the new
  // calibration is live and verified (OK, slot B), as the next boot confirms.
  FakeFlash landed;
  landed.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  landed.lands_but_fails_at = 2;
  int slot = -5;
  CHECK(Update(landed, Build(StandardBlob(6)), &slot) == METRO_FW_OK);
  CHECK(slot == 1);
  CHECK(Load(landed).seq == 6u);
  // The word did not land: the old calibration stays and the result says so.
  FakeFlash lost;
  lost.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  lost.fail_at = 2;
  CHECK(Update(lost, Build(StandardBlob(6)), &slot) == METRO_FW_E_FLASH);
  CHECK(slot == METRO_FW_SLOT_NONE);
  CHECK(Load(lost).seq == 5u);
  // The word did not land but the callback said yes: the read-back shows the slot invalid.
  FakeFlash lying;
  lying.Program(METRO_FW_SLOT_A_ADDR, Build(StandardBlob(5)));
  lying.stuck_byte = 0;  // the first byte of the commit word never programs
  CHECK(Update(lying, Build(StandardBlob(6)), &slot) == METRO_FW_E_VERIFY);
  CHECK(slot == METRO_FW_SLOT_NONE);
  CHECK(Load(lying).seq == 5u);
}
