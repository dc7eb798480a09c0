#include "metro_fw/update.h"

#include "le.h"

int metro_fw_update(const metro_fw_flash* flash, const uint32_t device_id[2], const uint8_t* blob,
                    uint32_t len, int* slot_written) {
  metro_fw_buffer in;
  metro_fw_blob_info new_info, slot_info[2];
  int result[2];
  int active, target, rc, committed;
  uint32_t base, off;
  metro_fw_slot reader;
  if (slot_written != 0) *slot_written = METRO_FW_SLOT_NONE;
  if (flash == 0 || flash->read == 0 || flash->erase_page == 0 || flash->write == 0 ||
      device_id == 0 || blob == 0) {
    return METRO_FW_E_ARG;
  }
  in.data = blob;
  in.len = len;
  rc = metro_fw_blob_validate(metro_fw_buffer_read, &in, len, device_id, &new_info);
  if (rc != METRO_FW_OK) return rc;
  if (new_info.total_len != len) return METRO_FW_E_BOUNDS; /* trailing bytes */
  active = metro_fw_choose_active(flash, device_id, slot_info, result);
  if (active != METRO_FW_SLOT_NONE && new_info.seq <= slot_info[active].seq) {
    return METRO_FW_E_STALE_SEQ; /* also covers an active seq of METRO_FW_SEQ_MAX */
  }
  target = active == 0 ? 1 : 0;
  base = flash->slot_addr[target];
  if (flash->erase_page(flash->ctx, base) != 0) return METRO_FW_E_FLASH;
  if (flash->write(flash->ctx, base + 4u, blob + 4, (uint32_t)new_info.total_len - 4u) != 0) {
    return METRO_FW_E_FLASH;
  }
  for (off = 4u; off < new_info.total_len; off += 16u) {
    uint8_t back[16];
    uint32_t n = new_info.total_len - off < 16u ? new_info.total_len - off : 16u;
    uint32_t i;
    if (flash->read(flash->ctx, base + off, back, n) != 0) return METRO_FW_E_FLASH;
    for (i = 0; i < n; ++i) {
      if (back[i] != blob[off + i]) return METRO_FW_E_VERIFY;
    }
  }
  committed = flash->write(flash->ctx, base, blob, 4u) == 0; /* the commit word */
  /* From here on the slot decides, as the next boot will: read back through the validator. */
  reader.flash = flash;
  reader.base = base;
  /* Valid means identical to the blob (its body was read back identical before the commit)
   * and, with its seq above the other slot's, active. */
  rc = metro_fw_blob_validate(metro_fw_slot_read, &reader, METRO_FW_PAGE_SIZE, device_id, 0);
  if (rc != METRO_FW_OK) {
    /* After a written commit word over a body read back identical the new calibration is
     * live: a failed read of the slot cannot say otherwise (other failures say it is not). */
    rc = !committed               ? METRO_FW_E_FLASH
         : rc == METRO_FW_E_FLASH ? METRO_FW_LIVE_UNVERIFIED
                                  : METRO_FW_E_VERIFY;
  }
  if (rc >= 0 && slot_written != 0) *slot_written = target;
  return rc;
}
