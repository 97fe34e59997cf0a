/* cavatar_protocol.h: C reference of the carpet wire protocol, firmware side.
 *
 * Every packet on the wire (all multi-byte fields little-endian):
 *
 *   +------------------------- COBS-encoded --------------------------+
 *   | type u8 | seq u16 | fields (table in protocol.toml) | crc16 u16 | 0x00
 *   +-----------------------------------------------------------------+
 *
 *   crc16 = CRC-16/CCITT-FALSE (poly 0x1021, no reflection, no final xor) over
 *           type..last field, seeded with CAV_DEFINITION_HASH, or CAV_FIXED_SEED
 *           for INFO and GET_INFO (so any host can always read who the device is).
 *
 *   ROW:  02 | seq | frame_seq u32 | t_us u32 | row u16 | count u16 | packing u8 | samples | crc16
 *         samples: u8       s0 s1 s2 ...                     (count bytes)
 *                  packed12 [s0 lo8][s0 hi4 | s1 lo4 << 4][s1 hi8] ...  ((3*count+1)/2 bytes;
 *                           an odd count ends with [s lo8][s hi4])
 *                  u16      s0 lo, s0 hi, s1 lo, ...          (2*count bytes)
 *
 * Offsets and sizes of every field come from cavatar_protocol_defs.h, generated
 * from protocol.toml by `python -m firmware_protocol.gen_c`.
 *
 * Rules: C99, no globals, no malloc, no struct punning. Encoders write the whole
 * wire packet (COBS + 0x00 delimiter) into a caller buffer and return its length,
 * or a negative CAV_ERR_*; a buffer of CAV_MAX_ENCODED_BYTES always suffices. The
 * sender owns the seq counter: +1 per packet sent, wrapping at 65536.
 * The command decoder takes one byte at a time, keeps its state in a caller-owned
 * cav_cmd_decoder, returns to idle on any error and counts each drop by reason.
 */
#ifndef CAVATAR_PROTOCOL_H
#define CAVATAR_PROTOCOL_H

#include <stddef.h>
#include <stdint.h>

#include "cavatar_protocol_defs.h"

#define CAV_ERR_ARG (-1)   /* a NULL pointer, or a value the packet cannot carry */
#define CAV_ERR_SPACE (-2) /* the caller's buffer is too small; nothing useful was written */

/* ---------------------------------------------------------------- checksums */

/* CRC-16/CCITT-FALSE, continuing from crc (start with the packet's seed). */
uint16_t cav_crc16(uint16_t crc, const uint8_t *data, size_t len);

/* CRC-32 as zlib.crc32: cav_crc32(0, a, n) == zlib.crc32(a); chain calls for more data. */
uint32_t cav_crc32(uint32_t crc, const uint8_t *data, size_t len);

/* FRAME_END's CRC-32 over samples as u16 little-endian; start at 0 and call once per
 * row in ascending row index, whatever the ROW packing. */
uint32_t cav_crc32_samples(uint32_t crc, const uint16_t *samples, size_t count);

/* COBS-encode len bytes into out (no delimiter); returns the encoded length, or
 * CAV_ERR_SPACE. Needs at most len + len / 254 + 1 bytes. */
int cav_cobs_encode(const uint8_t *data, size_t len, uint8_t *out, size_t cap);

/* ---------------------------------------------------------------- device -> host */

typedef struct {
    uint8_t fw_major, fw_minor, fw_patch;
    char device_id[16]; /* ASCII, NUL-padded; need not be NUL-terminated */
    uint16_t rows, cols;
    uint8_t tile_rows, tile_cols;
    uint8_t adc_bits;
    uint8_t packing; /* CAV_PACKING_* */
    int8_t sign;     /* CAV_SIGN_* */
    uint32_t rate_mhz;
    uint8_t flags;
} cav_info; /* protocol_version and definition_hash are written from the build's constants */

typedef struct {
    uint32_t frame_seq, t_us;
    uint16_t row;
    uint8_t packing;          /* CAV_PACKING_* */
    const uint16_t *samples;  /* count values, each within the packing's range */
    uint16_t count;
} cav_row;

typedef struct {
    uint32_t frame_seq, t_us;
    uint16_t rows;
    uint32_t scan_time_us, frame_crc32;
} cav_frame_end;

typedef struct {
    uint32_t t_us, uptime_s, frames_scanned, frames_dropped, adc_errors;
    uint32_t rx_bad_crc, rx_bad_framing, tx_overflows;
    int16_t temperature_cdeg; /* -32768: no sensor */
    uint16_t gain_step;       /* 65535: no gain control */
} cav_status;

int cav_encode_info(uint8_t *out, size_t cap, uint16_t seq, const cav_info *info);
int cav_encode_row(uint8_t *out, size_t cap, uint16_t seq, const cav_row *row);
int cav_encode_frame_end(uint8_t *out, size_t cap, uint16_t seq, const cav_frame_end *fe);
int cav_encode_status(uint8_t *out, size_t cap, uint16_t seq, const cav_status *st);
int cav_encode_ack(uint8_t *out, size_t cap, uint16_t seq, uint8_t cmd_type, uint16_t cmd_seq, uint32_t value);
int cav_encode_nak(uint8_t *out, size_t cap, uint16_t seq, uint8_t cmd_type, uint16_t cmd_seq, uint8_t reason);

/* ---------------------------------------------------------------- host -> device */

typedef struct {
    uint8_t type; /* CAV_TYPE_GET_INFO .. CAV_TYPE_PING */
    uint16_t seq;
    uint32_t rate_mhz;  /* SET_RATE, else 0 */
    uint16_t gain_step; /* SET_GAIN, else 0 */
    uint32_t token;     /* PING, else 0 */
} cav_command;

typedef enum {
    CAV_RX_NONE = 0,    /* byte taken, nothing complete yet */
    CAV_RX_COMMAND = 1, /* *out holds a command */
    CAV_RX_DROPPED = 2  /* a packet was dropped; the reason is in last_drop */
} cav_rx_event;

typedef struct {
    /* framing: the COBS chunk in progress */
    uint16_t encoded_len; /* bytes since the last delimiter */
    uint8_t code;         /* code byte of the current COBS block; 0 before the first */
    uint8_t block_left;   /* data bytes still due in the current block */
    uint8_t discarding;   /* skipping an over-long chunk up to the next delimiter */
    /* the decoded packet in progress */
    uint16_t n;                           /* decoded bytes so far (only the first are kept) */
    uint8_t buf[CAV_MAX_COMMAND_BYTES - CAV_CRC_BYTES]; /* the first decoded bytes (a command's body) */
    uint8_t last2[2];                     /* the newest two bytes: the CRC once the chunk ends */
    uint16_t crc;                         /* CRC of the bytes before last2 */
    /* sequence numbers of accepted commands */
    uint16_t last_seq;
    uint8_t have_seq;
    /* counters (never reset by the decoder) */
    uint32_t bytes_in, commands, missed, repeated;
    uint32_t dropped[CAV_DROP_REASON_COUNT];
    uint8_t last_drop; /* CAV_DROP_* of the latest CAV_RX_DROPPED */
} cav_cmd_decoder;

void cav_cmd_decoder_init(cav_cmd_decoder *dec);

/* Take one received byte. Returns CAV_RX_COMMAND with *out filled when it completes a
 * command, CAV_RX_DROPPED when it completes (or overfills) a packet that is refused. */
cav_rx_event cav_cmd_decoder_push(cav_cmd_decoder *dec, uint8_t byte, cav_command *out);

/* Take up to len bytes, stopping after the first byte that yields an event; *used says
 * how many were taken. Call again with the rest. */
cav_rx_event cav_cmd_decoder_feed(cav_cmd_decoder *dec, const uint8_t *data, size_t len, size_t *used,
                                  cav_command *out);

/* "bad_crc" etc. for a CAV_DROP_* (the names of firmware_protocol.codec.DROP_REASONS). */
const char *cav_drop_reason_name(unsigned reason);

#endif /* CAVATAR_PROTOCOL_H */
