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
 * validate (boot rules + seq above the active slot's), erase the inactive page, write all but
 * the magic word, read back and compare, write the magic word, re-validate the slot.
 * A power cut at any point leaves the old or the new calibration active.
 * *slot_written (may be NULL) receives the slot written, or METRO_FW_SLOT_NONE.
 * Returns METRO_FW_OK, METRO_FW_E_ARG, any validator code for the new blob,
 * METRO_FW_E_STALE_SEQ (seq not above the active slot's, or the active seq is
 * METRO_FW_SEQ_MAX), METRO_FW_E_FLASH (a callback failed), METRO_FW_E_VERIFY (read-back
 * or re-validation differs). */
int metro_fw_update(const metro_fw_flash* flash, const uint32_t device_id[2], const uint8_t* blob,
                    uint32_t len, int* slot_written);

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_UPDATE_H_ */
