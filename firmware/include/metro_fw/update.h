/* Power-fail-safe update of the calibration slots (docs/calibration-blob.md section 6). */
#ifndef METRO_FW_UPDATE_H_
#define METRO_FW_UPDATE_H_

#include <stdint.h>

#include "metro_fw/blob.h"
#include "metro_fw/flash.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Writes the blob (len bytes in RAM, magic included) into the inactive slot:
 * validate (boot rules, len == total_len, seq above the active slot's), erase the inactive
 * page, write all but the magic word, read back and compare, write the magic word, read the
 * slot back through the validator. A power cut at any point leaves the old or the new
 * calibration active (docs/calibration-blob.md section 6).
 *
 * A result >= 0 means the new calibration is live (what the next boot loads), any negative
 * result that the slot active before is still the active one (or none, if none was):
 *   METRO_FW_OK               written, committed and read back valid;
 *   METRO_FW_LIVE_UNVERIFIED  the commit word was written over a body read back identical,
 *                             but the final read-back could not read the slot (a read
 *                             callback failed): live, unverified;
 *   METRO_FW_E_ARG, any validator code for the new blob, METRO_FW_E_BOUNDS (len is not the
 *   blob's total_len), METRO_FW_E_STALE_SEQ (seq not above the active slot's, or the active
 *   seq is METRO_FW_SEQ_MAX), METRO_FW_E_FLASH (a callback failed; if it was the commit
 *   word's write, the read-back did not show the new slot valid), METRO_FW_E_VERIFY (the
 *   body read back differs, or the committed slot reads back invalid).
 * *slot_written (may be NULL) receives the slot written when the result is >= 0, else
 * METRO_FW_SLOT_NONE. */
int metro_fw_update(const metro_fw_flash* flash, const uint32_t device_id[2], const uint8_t* blob,
                    uint32_t len, int* slot_written);

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_UPDATE_H_ */
