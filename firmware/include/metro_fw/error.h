/* Error codes shared by every metro_fw function (docs/calibration-blob.md section 9).
 *
 * Every function of the library returns int: METRO_FW_OK (0) on success or one of the
 * negative codes below. Each function's comment lists the codes it can return. The one
 * positive code, METRO_FW_LIVE_UNVERIFIED, only metro_fw_update returns: there a result >= 0
 * means the new calibration is live. */
#ifndef METRO_FW_ERROR_H_
#define METRO_FW_ERROR_H_

#ifdef __cplusplus
extern "C" {
#endif

enum metro_fw_error {
  METRO_FW_OK = 0,
  METRO_FW_E_ARG = -1,         /* NULL pointer or argument out of range */
  METRO_FW_E_EMPTY = -2,       /* slot erased: magic 0xFFFFFFFF */
  METRO_FW_E_MAGIC = -3,       /* magic not "ICAL": tombstone, torn commit, garbage */
  METRO_FW_E_UNSUPPORTED = -4, /* fmt_major this firmware does not know */
  METRO_FW_E_BOUNDS = -5,      /* total_len/header_len out of bounds or beyond the data */
  METRO_FW_E_CRC = -6,         /* CRC-32 mismatch */
  METRO_FW_E_FOREIGN = -7,     /* device_id belongs to another chip */
  METRO_FW_E_SEQ = -8,         /* seq 0 or 0xFFFFFFFF */
  METRO_FW_E_SECTION = -9,     /* section walk failed */
  METRO_FW_E_FLASH = -10,      /* a flash callback reported an error */
  METRO_FW_E_VERIFY = -11,     /* read-back differs from what was written */
  METRO_FW_E_STALE_SEQ = -12,  /* seq not above the active slot's, or seq exhausted */
  METRO_FW_E_FRAME = -13,      /* push frame: bad CRC-16, length or SLIP escape */
  METRO_FW_E_SENSOR = -14,     /* flags disagree with the sections, or a declared sensor is
                                  absent, NaN/Inf, of unknown model bits or outside its limits */
  /* Not an error: metro_fw_update wrote the commit word and the new calibration is live, but
     the read-back through the validator could not read the slot (docs section 6). */
  METRO_FW_LIVE_UNVERIFIED = 1
};

#ifdef __cplusplus
}
#endif

#endif /* METRO_FW_ERROR_H_ */
