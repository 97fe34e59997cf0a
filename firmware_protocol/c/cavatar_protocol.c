/* cavatar_protocol.c: C reference of the carpet wire protocol, firmware side.
 *
 *   raw packet:  type u8 | seq u16 | fields ... | crc16 u16         (little-endian)
 *   on the wire: COBS(raw packet) 0x00
 *
 *   COBS: the packet is cut at each 0x00 into blocks, each sent as
 *         [code = len(data) + 1][data...] with the zero implied; a run of 254
 *         non-zero bytes is sent as [0xFF][254 bytes] with no implied zero. The
 *         last block's code is always written (so 254 bytes end in 0x01), exactly
 *         as firmware_protocol/cobs.py does.
 *
 *   INFO       01 | seq | protocol_version u16 | definition_hash u16 | fw x3 u8 | device_id 16 |
 *                   rows u16 | cols u16 | tile_rows u8 | tile_cols u8 | adc_bits u8 | packing u8 |
 *                   sign i8 | rate_mhz u32 | flags u8                             (seed 0xFFFF)
 *   ROW        02 | seq | frame_seq u32 | t_us u32 | row u16 | count u16 | packing u8 | samples
 *   FRAME_END  03 | seq | frame_seq u32 | t_us u32 | rows u16 | scan_time_us u32 | frame_crc32 u32
 *   STATUS     04 | seq | t_us, uptime_s, frames_scanned, frames_dropped, adc_errors,
 *                   rx_bad_crc, rx_bad_framing, tx_overflows u32 | temperature_cdeg i16 | gain_step u16
 *   ACK        05 | seq | cmd_type u8 | cmd_seq u16 | value u32
 *   NAK        06 | seq | cmd_type u8 | cmd_seq u16 | reason u8
 *   GET_INFO   81 | seq                         (seed 0xFFFF)
 *   START      82 | seq             STOP 83 | seq
 *   SET_RATE   84 | seq | rate_mhz u32
 *   SET_GAIN   85 | seq | gain_step u16
 *   PING       86 | seq | token u32
 *
 * The byte offsets are the generated CAV_<PACKET>_<FIELD>_OFFSET of cavatar_protocol_defs.h.
 */
#include "cavatar_protocol.h"

#include <limits.h>
#include <string.h>

#define SEED(fixed) ((uint16_t)((fixed) ? CAV_FIXED_SEED : CAV_DEFINITION_HASH))

/* ---------------------------------------------------------------- bytes and checksums */

static void put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

static void put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

static uint16_t get_u16(const uint8_t *p)
{
    return (uint16_t)(p[0] | ((unsigned)p[1] << 8));
}

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put_header(uint8_t *body, uint8_t type, uint16_t seq)
{
    body[0] = type;
    put_u16(body + 1, seq);
}

static uint16_t crc16_byte(uint16_t crc, uint8_t byte)
{
    unsigned c = crc ^ ((unsigned)byte << 8);
    int bit;
    for (bit = 0; bit < 8; bit++)
        c = (c & 0x8000u) ? (c << 1) ^ 0x1021u : c << 1;
    return (uint16_t)(c & 0xFFFFu);
}

uint16_t cav_crc16(uint16_t crc, const uint8_t *data, size_t len)
{
    size_t i;
    for (i = 0; i < len; i++)
        crc = crc16_byte(crc, data[i]);
    return crc;
}

uint32_t cav_crc32(uint32_t crc, const uint8_t *data, size_t len)
{
    size_t i;
    int bit;
    crc = ~crc;
    for (i = 0; i < len; i++) {
        crc ^= data[i];
        for (bit = 0; bit < 8; bit++)
            crc = (crc & 1u) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
    }
    return ~crc;
}

uint32_t cav_crc32_samples(uint32_t crc, const uint16_t *samples, size_t count)
{
    size_t i;
    uint8_t le[2];
    for (i = 0; i < count; i++) {
        put_u16(le, samples[i]);
        crc = cav_crc32(crc, le, 2);
    }
    return crc;
}

/* ---------------------------------------------------------------- COBS writer
 * Stuffs bytes into out as they come, computing the CRC on the way. Writes past cap
 * are not made; they set overflow, and the encoder then returns CAV_ERR_SPACE. */

typedef struct {
    uint8_t *out;
    size_t cap, pos; /* pos: next free byte */
    size_t code_pos; /* where the current block's code byte goes */
    uint8_t code;    /* len(current block) + 1 */
    uint16_t crc;
    int overflow;
} writer;

static void w_store(writer *w, size_t at, uint8_t b)
{
    if (at < w->cap)
        w->out[at] = b;
    else
        w->overflow = 1;
}

static void w_begin(writer *w, uint8_t *out, size_t cap, uint16_t seed)
{
    w->out = out;
    w->cap = out ? cap : 0;
    w->code_pos = 0;
    w->pos = 1;
    w->code = 1;
    w->crc = seed;
    w->overflow = 0;
}

static void w_cobs(writer *w, uint8_t b)
{
    if (b != 0) {
        w_store(w, w->pos++, b);
        if (++w->code != 0xFF)
            return;
    }
    w_store(w, w->code_pos, w->code); /* a zero, or 254 data bytes: close the block */
    w->code_pos = w->pos++;
    w->code = 1;
}

static void w_byte(writer *w, uint8_t b)
{
    w->crc = crc16_byte(w->crc, b);
    w_cobs(w, b);
}

static void w_bytes(writer *w, const uint8_t *p, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        w_byte(w, p[i]);
}

static int w_finish_cobs(writer *w)
{
    w_store(w, w->code_pos, w->code);
    return w->overflow ? CAV_ERR_SPACE : (int)w->pos;
}

static int w_end_packet(writer *w)
{
    uint16_t crc = w->crc;
    w_cobs(w, (uint8_t)(crc & 0xFFu));
    w_cobs(w, (uint8_t)(crc >> 8));
    w_store(w, w->code_pos, w->code);
    w_store(w, w->pos++, 0x00); /* delimiter */
    return w->overflow ? CAV_ERR_SPACE : (int)w->pos;
}

int cav_cobs_encode(const uint8_t *data, size_t len, uint8_t *out, size_t cap)
{
    writer w;
    if ((data == NULL && len > 0) || len > (size_t)INT_MAX / 2)
        return CAV_ERR_ARG;
    w_begin(&w, out, cap, 0);
    while (len--)
        w_cobs(&w, *data++);
    return w_finish_cobs(&w);
}

static int encode_body(uint8_t *out, size_t cap, int seed_fixed, const uint8_t *body, size_t n)
{
    writer w;
    w_begin(&w, out, cap, SEED(seed_fixed));
    w_bytes(&w, body, n);
    return w_end_packet(&w);
}

/* ---------------------------------------------------------------- device -> host encoders */

int cav_encode_info(uint8_t *out, size_t cap, uint16_t seq, const cav_info *info)
{
    uint8_t b[CAV_INFO_BODY_BYTES];
    int i;
    if (info == NULL || info->packing > CAV_PACKING_U16 ||
        (info->sign != CAV_SIGN_DECREASES && info->sign != CAV_SIGN_INCREASES))
        return CAV_ERR_ARG;
    put_header(b, CAV_TYPE_INFO, seq);
    put_u16(b + CAV_INFO_PROTOCOL_VERSION_OFFSET, CAV_PROTOCOL_VERSION);
    put_u16(b + CAV_INFO_DEFINITION_HASH_OFFSET, CAV_DEFINITION_HASH);
    b[CAV_INFO_FW_MAJOR_OFFSET] = info->fw_major;
    b[CAV_INFO_FW_MINOR_OFFSET] = info->fw_minor;
    b[CAV_INFO_FW_PATCH_OFFSET] = info->fw_patch;
    for (i = 0; i < CAV_INFO_DEVICE_ID_SIZE; i++)
        b[CAV_INFO_DEVICE_ID_OFFSET + i] = (uint8_t)info->device_id[i];
    put_u16(b + CAV_INFO_ROWS_OFFSET, info->rows);
    put_u16(b + CAV_INFO_COLS_OFFSET, info->cols);
    b[CAV_INFO_TILE_ROWS_OFFSET] = info->tile_rows;
    b[CAV_INFO_TILE_COLS_OFFSET] = info->tile_cols;
    b[CAV_INFO_ADC_BITS_OFFSET] = info->adc_bits;
    b[CAV_INFO_PACKING_OFFSET] = info->packing;
    b[CAV_INFO_SIGN_OFFSET] = (uint8_t)info->sign; /* two's complement byte, by C's modulo rule */
    put_u32(b + CAV_INFO_RATE_MHZ_OFFSET, info->rate_mhz);
    b[CAV_INFO_FLAGS_OFFSET] = info->flags;
    return encode_body(out, cap, CAV_INFO_SEED_FIXED, b, sizeof b);
}

static size_t packed_size(uint16_t count, uint8_t packing)
{
    if (packing == CAV_PACKING_U8)
        return count;
    if (packing == CAV_PACKING_PACKED12)
        return (3u * (size_t)count + 1u) / 2u;
    return 2u * (size_t)count;
}

int cav_encode_row(uint8_t *out, size_t cap, uint16_t seq, const cav_row *row)
{
    uint8_t b[CAV_ROW_BODY_BYTES];
    uint16_t limit, i;
    const uint16_t *s;
    writer w;
    if (row == NULL || (row->samples == NULL && row->count > 0))
        return CAV_ERR_ARG;
    switch (row->packing) {
    case CAV_PACKING_U8: limit = 0xFFu; break;
    case CAV_PACKING_PACKED12: limit = 0xFFFu; break;
    case CAV_PACKING_U16: limit = 0xFFFFu; break;
    default: return CAV_ERR_ARG;
    }
    if (CAV_ROW_BODY_BYTES + packed_size(row->count, row->packing) + CAV_CRC_BYTES > CAV_MAX_PACKET_BYTES)
        return CAV_ERR_ARG;
    for (i = 0; i < row->count; i++)
        if (row->samples[i] > limit)
            return CAV_ERR_ARG;

    put_header(b, CAV_TYPE_ROW, seq);
    put_u32(b + CAV_ROW_FRAME_SEQ_OFFSET, row->frame_seq);
    put_u32(b + CAV_ROW_T_US_OFFSET, row->t_us);
    put_u16(b + CAV_ROW_ROW_OFFSET, row->row);
    put_u16(b + CAV_ROW_COUNT_OFFSET, row->count);
    b[CAV_ROW_PACKING_OFFSET] = row->packing;
    w_begin(&w, out, cap, SEED(CAV_ROW_SEED_FIXED));
    w_bytes(&w, b, sizeof b);

    s = row->samples;
    if (row->packing == CAV_PACKING_U8) {
        for (i = 0; i < row->count; i++)
            w_byte(&w, (uint8_t)s[i]);
    } else if (row->packing == CAV_PACKING_U16) {
        for (i = 0; i < row->count; i++) {
            w_byte(&w, (uint8_t)(s[i] & 0xFFu));
            w_byte(&w, (uint8_t)(s[i] >> 8));
        }
    } else { /* packed12: [a lo8][a hi4 | b lo4 << 4][b hi8]; an odd count ends [a lo8][a hi4] */
        for (i = 0; i + 1u < row->count; i += 2u) {
            w_byte(&w, (uint8_t)(s[i] & 0xFFu));
            w_byte(&w, (uint8_t)((s[i] >> 8) | ((s[i + 1u] & 0x0Fu) << 4)));
            w_byte(&w, (uint8_t)(s[i + 1u] >> 4));
        }
        if (row->count % 2u) {
            w_byte(&w, (uint8_t)(s[i] & 0xFFu));
            w_byte(&w, (uint8_t)(s[i] >> 8));
        }
    }
    return w_end_packet(&w);
}

int cav_encode_frame_end(uint8_t *out, size_t cap, uint16_t seq, const cav_frame_end *fe)
{
    uint8_t b[CAV_FRAME_END_BODY_BYTES];
    if (fe == NULL)
        return CAV_ERR_ARG;
    put_header(b, CAV_TYPE_FRAME_END, seq);
    put_u32(b + CAV_FRAME_END_FRAME_SEQ_OFFSET, fe->frame_seq);
    put_u32(b + CAV_FRAME_END_T_US_OFFSET, fe->t_us);
    put_u16(b + CAV_FRAME_END_ROWS_OFFSET, fe->rows);
    put_u32(b + CAV_FRAME_END_SCAN_TIME_US_OFFSET, fe->scan_time_us);
    put_u32(b + CAV_FRAME_END_FRAME_CRC32_OFFSET, fe->frame_crc32);
    return encode_body(out, cap, CAV_FRAME_END_SEED_FIXED, b, sizeof b);
}

int cav_encode_status(uint8_t *out, size_t cap, uint16_t seq, const cav_status *st)
{
    uint8_t b[CAV_STATUS_BODY_BYTES];
    if (st == NULL)
        return CAV_ERR_ARG;
    put_header(b, CAV_TYPE_STATUS, seq);
    put_u32(b + CAV_STATUS_T_US_OFFSET, st->t_us);
    put_u32(b + CAV_STATUS_UPTIME_S_OFFSET, st->uptime_s);
    put_u32(b + CAV_STATUS_FRAMES_SCANNED_OFFSET, st->frames_scanned);
    put_u32(b + CAV_STATUS_FRAMES_DROPPED_OFFSET, st->frames_dropped);
    put_u32(b + CAV_STATUS_ADC_ERRORS_OFFSET, st->adc_errors);
    put_u32(b + CAV_STATUS_RX_BAD_CRC_OFFSET, st->rx_bad_crc);
    put_u32(b + CAV_STATUS_RX_BAD_FRAMING_OFFSET, st->rx_bad_framing);
    put_u32(b + CAV_STATUS_TX_OVERFLOWS_OFFSET, st->tx_overflows);
    put_u16(b + CAV_STATUS_TEMPERATURE_CDEG_OFFSET, (uint16_t)st->temperature_cdeg); /* two's complement */
    put_u16(b + CAV_STATUS_GAIN_STEP_OFFSET, st->gain_step);
    return encode_body(out, cap, CAV_STATUS_SEED_FIXED, b, sizeof b);
}

int cav_encode_ack(uint8_t *out, size_t cap, uint16_t seq, uint8_t cmd_type, uint16_t cmd_seq, uint32_t value)
{
    uint8_t b[CAV_ACK_BODY_BYTES];
    put_header(b, CAV_TYPE_ACK, seq);
    b[CAV_ACK_CMD_TYPE_OFFSET] = cmd_type;
    put_u16(b + CAV_ACK_CMD_SEQ_OFFSET, cmd_seq);
    put_u32(b + CAV_ACK_VALUE_OFFSET, value);
    return encode_body(out, cap, CAV_ACK_SEED_FIXED, b, sizeof b);
}

int cav_encode_nak(uint8_t *out, size_t cap, uint16_t seq, uint8_t cmd_type, uint16_t cmd_seq, uint8_t reason)
{
    uint8_t b[CAV_NAK_BODY_BYTES];
    put_header(b, CAV_TYPE_NAK, seq);
    b[CAV_NAK_CMD_TYPE_OFFSET] = cmd_type;
    put_u16(b + CAV_NAK_CMD_SEQ_OFFSET, cmd_seq);
    b[CAV_NAK_REASON_OFFSET] = reason;
    return encode_body(out, cap, CAV_NAK_SEED_FIXED, b, sizeof b);
}

/* ---------------------------------------------------------------- host -> device decoder
 * Per chunk (bytes between delimiters), checked in the Python decoder's order:
 *   longer than CAV_MAX_CHUNK_BYTES -> too_long (at once; the rest is skipped)
 *   a COBS block running past the delimiter -> bad_cobs
 *   fewer than 5 decoded bytes -> too_short
 *   CRC (seeded by the type's seed kind) -> bad_crc
 *   not a command -> unknown_type;  length != the command's -> bad_length
 * Only the first bytes (up to the longest command body) are kept; the CRC runs over every
 * byte as it arrives, two bytes behind, so a long packet is judged like a short one. */

static void rx_restart(cav_cmd_decoder *d)
{
    d->encoded_len = 0;
    d->code = 0;
    d->block_left = 0;
    d->discarding = 0;
    d->n = 0;
}

void cav_cmd_decoder_init(cav_cmd_decoder *dec)
{
    if (dec != NULL)
        memset(dec, 0, sizeof *dec);
}

static cav_rx_event rx_drop(cav_cmd_decoder *d, uint8_t reason)
{
    d->dropped[reason]++;
    d->last_drop = reason;
    return CAV_RX_DROPPED;
}

static void rx_take(cav_cmd_decoder *d, uint8_t b) /* one decoded byte */
{
    if (d->n == 0)
        d->crc = SEED(CAV_SEED_IS_FIXED(b));
    else if (d->n >= 2)
        d->crc = crc16_byte(d->crc, d->last2[0]);
    d->last2[0] = d->last2[1];
    d->last2[1] = b;
    if (d->n < sizeof d->buf)
        d->buf[d->n] = b;
    d->n++;
}

static cav_rx_event rx_command(cav_cmd_decoder *d, cav_command *out)
{
    const uint8_t *b = d->buf;
    uint16_t body = (uint16_t)(d->n - CAV_CRC_BYTES), want, gap;
    switch (b[0]) {
    case CAV_TYPE_GET_INFO: want = CAV_GET_INFO_BODY_BYTES; break;
    case CAV_TYPE_START: want = CAV_START_BODY_BYTES; break;
    case CAV_TYPE_STOP: want = CAV_STOP_BODY_BYTES; break;
    case CAV_TYPE_SET_RATE: want = CAV_SET_RATE_BODY_BYTES; break;
    case CAV_TYPE_SET_GAIN: want = CAV_SET_GAIN_BODY_BYTES; break;
    case CAV_TYPE_PING: want = CAV_PING_BODY_BYTES; break;
    default: return rx_drop(d, CAV_DROP_UNKNOWN_TYPE); /* includes device->host types */
    }
    if (body != want)
        return rx_drop(d, CAV_DROP_BAD_LENGTH);

    memset(out, 0, sizeof *out);
    out->type = b[0];
    out->seq = get_u16(b + 1);
    if (b[0] == CAV_TYPE_SET_RATE)
        out->rate_mhz = get_u32(b + CAV_SET_RATE_RATE_MHZ_OFFSET);
    else if (b[0] == CAV_TYPE_SET_GAIN)
        out->gain_step = get_u16(b + CAV_SET_GAIN_GAIN_STEP_OFFSET);
    else if (b[0] == CAV_TYPE_PING)
        out->token = get_u32(b + CAV_PING_TOKEN_OFFSET);

    if (d->have_seq) { /* gaps as the Python decoder counts them */
        gap = (uint16_t)(out->seq - d->last_seq - 1u);
        if (gap == 0xFFFFu)
            d->repeated++;
        else if (gap < 0x8000u)
            d->missed += gap;
    }
    d->last_seq = out->seq;
    d->have_seq = 1;
    d->commands++;
    return CAV_RX_COMMAND;
}

static cav_rx_event rx_judge(cav_cmd_decoder *d, cav_command *out) /* at a delimiter */
{
    if (d->discarding || d->encoded_len == 0) /* the tail of an over-long chunk, or an idle 0x00 */
        return CAV_RX_NONE;
    if (d->block_left != 0)
        return rx_drop(d, CAV_DROP_BAD_COBS);
    if (d->n < CAV_MIN_PACKET_BYTES)
        return rx_drop(d, CAV_DROP_TOO_SHORT);
    if (d->crc != get_u16(d->last2))
        return rx_drop(d, CAV_DROP_BAD_CRC);
    return rx_command(d, out);
}

cav_rx_event cav_cmd_decoder_push(cav_cmd_decoder *dec, uint8_t byte, cav_command *out)
{
    if (dec == NULL || out == NULL)
        return CAV_RX_NONE;
    dec->bytes_in++;
    if (byte == 0x00) {
        cav_rx_event ev = rx_judge(dec, out);
        rx_restart(dec);
        return ev;
    }
    if (dec->discarding)
        return CAV_RX_NONE;
    if (++dec->encoded_len > CAV_MAX_CHUNK_BYTES) {
        rx_restart(dec);
        dec->discarding = 1;
        return rx_drop(dec, CAV_DROP_TOO_LONG);
    }
    if (dec->block_left == 0) { /* a code byte; the block before it, unless a full 0xFF one, ended in a zero */
        if (dec->code != 0 && dec->code != 0xFF)
            rx_take(dec, 0x00);
        dec->code = byte;
        dec->block_left = (uint8_t)(byte - 1u);
    } else {
        rx_take(dec, byte);
        dec->block_left--;
    }
    return CAV_RX_NONE;
}

cav_rx_event cav_cmd_decoder_feed(cav_cmd_decoder *dec, const uint8_t *data, size_t len, size_t *used,
                                  cav_command *out)
{
    size_t i;
    cav_rx_event ev;
    for (i = 0; i < len; i++) {
        ev = cav_cmd_decoder_push(dec, data[i], out);
        if (ev != CAV_RX_NONE) {
            if (used != NULL)
                *used = i + 1;
            return ev;
        }
    }
    if (used != NULL)
        *used = len;
    return CAV_RX_NONE;
}

const char *cav_drop_reason_name(unsigned reason)
{
    static const char *const names[CAV_DROP_REASON_COUNT] = CAV_DROP_REASON_NAMES;
    return reason < CAV_DROP_REASON_COUNT ? names[reason] : "unknown";
}
