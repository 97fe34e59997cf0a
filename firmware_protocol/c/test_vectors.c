/* test_vectors.c: checks the C reference against the shared vectors (vectors/vectors.jsonl).
 *
 * Input on stdin, one vector a line, tokens separated by spaces (written from the JSONL
 * by tests/firmware_protocol/test_c_reference.py):
 *
 *   E <name> <TYPE> <seq> <fields in protocol.toml order> [<samples>] <wire hex>
 *        device->host packet; INFO leaves out protocol_version and definition_hash (the
 *        build's constants) and gives device_id as 32 hex digits; ROW ends its fields
 *        with count, packing, then count samples.
 *   F <name> <frame_crc32> <nrows> { <count> <samples> }      FRAME_END's CRC-32 over rows
 *   D <name> <wire hex> <missed> <repeated> <nevents> { P <type> <seq> <value> | X <drop reason> }
 *        a host->device byte stream and what the command decoder must report, in order.
 *
 *   test_vectors          check every line, plus built-in edge cases; exit 1 on any mismatch
 *   test_vectors --emit   print "<name> <hex>" for each E line as this build encodes it
 *
 * Encoders write into heap buffers of exactly the expected size, and are called again
 * with one byte less, so the sanitizers catch any write past the caller's buffer.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cavatar_protocol.h"

#define MAX_LINE (1 << 17)
#define MAX_TOKENS 8192
#define MAX_EVENTS 256
#define MAX_SAMPLES 4096

typedef struct {
    const char *type;
    uint16_t seq;
    cav_info info;
    cav_row row;
    uint16_t samples[MAX_SAMPLES];
    cav_frame_end fe;
    cav_status st;
    uint8_t cmd_type, reason;
    uint16_t cmd_seq;
    uint32_t value;
} packet_args;

typedef struct {
    char kind; /* 'P' command, 'X' drop */
    uint8_t type;
    uint16_t seq;
    uint32_t value;
    unsigned reason;
} event;

typedef struct {
    size_t n;
    event ev[MAX_EVENTS];
    uint32_t missed, repeated;
} outcome;

static int failures;

static void fail(const char *name, const char *what)
{
    printf("FAIL %s: %s\n", name, what);
    failures++;
}

static long long num(const char *tok)
{
    char *end;
    long long v = strtoll(tok, &end, 10);
    if (*end != '\0') {
        fprintf(stderr, "not a number: %s\n", tok);
        exit(2);
    }
    return v;
}

static size_t unhex(const char *hex, uint8_t *out, size_t cap)
{
    size_t i, n = strlen(hex) / 2;
    unsigned byte;
    if (n > cap || strlen(hex) % 2) {
        fprintf(stderr, "bad hex (%lu chars)\n", (unsigned long)strlen(hex));
        exit(2);
    }
    for (i = 0; i < n; i++) {
        if (sscanf(hex + 2 * i, "%2x", &byte) != 1)
            exit(2);
        out[i] = (uint8_t)byte;
    }
    return n;
}

/* ---------------------------------------------------------------- encoders */

static void parse_packet(char **t, int nt, packet_args *a)
{
    int i = 0, k;
    uint8_t id[16];
    memset(a, 0, sizeof *a);
    a->type = t[i++];
    a->seq = (uint16_t)num(t[i++]);
    if (!strcmp(a->type, "INFO")) {
        a->info.fw_major = (uint8_t)num(t[i++]);
        a->info.fw_minor = (uint8_t)num(t[i++]);
        a->info.fw_patch = (uint8_t)num(t[i++]);
        unhex(t[i++], id, sizeof id);
        memcpy(a->info.device_id, id, sizeof id);
        a->info.rows = (uint16_t)num(t[i++]);
        a->info.cols = (uint16_t)num(t[i++]);
        a->info.tile_rows = (uint8_t)num(t[i++]);
        a->info.tile_cols = (uint8_t)num(t[i++]);
        a->info.adc_bits = (uint8_t)num(t[i++]);
        a->info.packing = (uint8_t)num(t[i++]);
        a->info.sign = (int8_t)num(t[i++]);
        a->info.rate_mhz = (uint32_t)num(t[i++]);
        a->info.flags = (uint8_t)num(t[i++]);
    } else if (!strcmp(a->type, "ROW")) {
        a->row.frame_seq = (uint32_t)num(t[i++]);
        a->row.t_us = (uint32_t)num(t[i++]);
        a->row.row = (uint16_t)num(t[i++]);
        a->row.count = (uint16_t)num(t[i++]);
        a->row.packing = (uint8_t)num(t[i++]);
        if (a->row.count > MAX_SAMPLES || i + a->row.count != nt) {
            fprintf(stderr, "ROW: count %u does not match its samples\n", a->row.count);
            exit(2);
        }
        for (k = 0; k < a->row.count; k++)
            a->samples[k] = (uint16_t)num(t[i + k]);
        a->row.samples = a->samples;
    } else if (!strcmp(a->type, "FRAME_END")) {
        a->fe.frame_seq = (uint32_t)num(t[i++]);
        a->fe.t_us = (uint32_t)num(t[i++]);
        a->fe.rows = (uint16_t)num(t[i++]);
        a->fe.scan_time_us = (uint32_t)num(t[i++]);
        a->fe.frame_crc32 = (uint32_t)num(t[i++]);
    } else if (!strcmp(a->type, "STATUS")) {
        a->st.t_us = (uint32_t)num(t[i++]);
        a->st.uptime_s = (uint32_t)num(t[i++]);
        a->st.frames_scanned = (uint32_t)num(t[i++]);
        a->st.frames_dropped = (uint32_t)num(t[i++]);
        a->st.adc_errors = (uint32_t)num(t[i++]);
        a->st.rx_bad_crc = (uint32_t)num(t[i++]);
        a->st.rx_bad_framing = (uint32_t)num(t[i++]);
        a->st.tx_overflows = (uint32_t)num(t[i++]);
        a->st.temperature_cdeg = (int16_t)num(t[i++]);
        a->st.gain_step = (uint16_t)num(t[i++]);
    } else if (!strcmp(a->type, "ACK") || !strcmp(a->type, "NAK")) {
        a->cmd_type = (uint8_t)num(t[i++]);
        a->cmd_seq = (uint16_t)num(t[i++]);
        a->value = (uint32_t)num(t[i++]);
    } else {
        fprintf(stderr, "unknown packet type %s\n", a->type);
        exit(2);
    }
}

static int encode(const packet_args *a, uint8_t *out, size_t cap)
{
    if (!strcmp(a->type, "INFO"))
        return cav_encode_info(out, cap, a->seq, &a->info);
    if (!strcmp(a->type, "ROW"))
        return cav_encode_row(out, cap, a->seq, &a->row);
    if (!strcmp(a->type, "FRAME_END"))
        return cav_encode_frame_end(out, cap, a->seq, &a->fe);
    if (!strcmp(a->type, "STATUS"))
        return cav_encode_status(out, cap, a->seq, &a->st);
    if (!strcmp(a->type, "ACK"))
        return cav_encode_ack(out, cap, a->seq, a->cmd_type, a->cmd_seq, a->value);
    return cav_encode_nak(out, cap, a->seq, a->cmd_type, a->cmd_seq, (uint8_t)a->value);
}

static void check_encode(const char *name, const packet_args *a, const char *wire_hex)
{
    uint8_t want[CAV_MAX_ENCODED_BYTES + 1];
    size_t n = unhex(wire_hex, want, sizeof want);
    uint8_t *exact = malloc(n), *short_buf = malloc(n - 1);
    int got;
    if (exact == NULL || short_buf == NULL)
        exit(2);
    got = encode(a, exact, n);
    if (got != (int)n)
        fail(name, "encoded length differs");
    else if (memcmp(exact, want, n) != 0)
        fail(name, "encoded bytes differ");
    if (encode(a, short_buf, n - 1) != CAV_ERR_SPACE)
        fail(name, "a buffer one byte short was not refused");
    free(exact);
    free(short_buf);
}

static void emit(const char *name, const packet_args *a)
{
    uint8_t out[CAV_MAX_ENCODED_BYTES];
    int i, n = encode(a, out, sizeof out);
    printf("%s ", name);
    for (i = 0; i < n; i++)
        printf("%02x", out[i]);
    printf("%s\n", n > 0 ? "" : "-");
}

static void check_frame_crc(char **t, int nt)
{
    uint32_t want = (uint32_t)num(t[1]), crc = 0;
    uint16_t s[MAX_SAMPLES];
    long nrows = (long)num(t[2]), r, k, count;
    int i = 3;
    for (r = 0; r < nrows; r++) {
        count = (long)num(t[i++]);
        if (count > MAX_SAMPLES || i + count > nt)
            exit(2);
        for (k = 0; k < count; k++)
            s[k] = (uint16_t)num(t[i++]);
        crc = cav_crc32_samples(crc, s, (size_t)count);
    }
    if (crc != want)
        fail(t[0], "frame CRC-32 differs");
}

/* ---------------------------------------------------------------- command decoder */

static uint32_t rng_next(uint32_t *x) /* xorshift32: reproducible split points */
{
    *x ^= *x << 13;
    *x ^= *x >> 17;
    *x ^= *x << 5;
    return *x;
}

static void record(outcome *o, cav_rx_event ev, const cav_cmd_decoder *d, const cav_command *c)
{
    event *e;
    if (ev == CAV_RX_NONE || o->n >= MAX_EVENTS)
        return;
    e = &o->ev[o->n++];
    memset(e, 0, sizeof *e);
    if (ev == CAV_RX_DROPPED) {
        e->kind = 'X';
        e->reason = d->last_drop;
        return;
    }
    e->kind = 'P';
    e->type = c->type;
    e->seq = c->seq;
    e->value = c->type == CAV_TYPE_SET_RATE ? c->rate_mhz : c->type == CAV_TYPE_SET_GAIN ? c->gain_step : c->token;
}

enum { BYTE_BY_BYTE, ALL_AT_ONCE, RANDOM_SPLITS };

/* Feed wire to a fresh decoder; RANDOM_SPLITS cuts it into chunks of 1..17 bytes drawn from seed. */
static void run_decoder(const uint8_t *wire, size_t len, int mode, uint32_t seed, outcome *o, const char *name)
{
    cav_cmd_decoder d;
    cav_command c;
    size_t pos = 0, chunk, used, i, drops = 0, commands = 0;
    cav_rx_event ev;
    memset(o, 0, sizeof *o);
    cav_cmd_decoder_init(&d);
    while (pos < len) {
        chunk = mode == BYTE_BY_BYTE ? 1 : mode == ALL_AT_ONCE ? len - pos : 1 + rng_next(&seed) % 17;
        if (chunk > len - pos)
            chunk = len - pos;
        if (mode == BYTE_BY_BYTE) {
            record(o, cav_cmd_decoder_push(&d, wire[pos], &c), &d, &c);
            pos++;
            continue;
        }
        while (chunk > 0) {
            ev = cav_cmd_decoder_feed(&d, wire + pos, chunk, &used, &c);
            record(o, ev, &d, &c);
            pos += used;
            chunk -= used;
        }
    }
    o->missed = d.missed;
    o->repeated = d.repeated;
    for (i = 0; i < o->n; i++) {
        if (o->ev[i].kind == 'X')
            drops++;
        else
            commands++;
    }
    for (i = 0; i < CAV_DROP_REASON_COUNT; i++)
        drops -= d.dropped[i];
    if (drops != 0 || commands != d.commands || d.bytes_in != len)
        fail(name, "decoder counters disagree with its events");
}

static void check_decode(char **t, int nt)
{
    static uint8_t wire[2 * CAV_MAX_ENCODED_BYTES + 256];
    outcome want, got;
    const char *name = t[0];
    size_t len = unhex(t[1], wire, sizeof wire), k;
    int i = 5;
    unsigned run;
    memset(&want, 0, sizeof want);
    want.missed = (uint32_t)num(t[2]);
    want.repeated = (uint32_t)num(t[3]);
    want.n = (size_t)num(t[4]);
    for (k = 0; k < want.n && i < nt; k++) {
        event *e = &want.ev[k];
        e->kind = t[i++][0];
        if (e->kind == 'P') {
            e->type = (uint8_t)num(t[i++]);
            e->seq = (uint16_t)num(t[i++]);
            e->value = (uint32_t)num(t[i++]);
        } else {
            const char *reason = t[i++];
            for (e->reason = 0; e->reason < CAV_DROP_REASON_COUNT; e->reason++)
                if (!strcmp(reason, cav_drop_reason_name(e->reason)))
                    break;
        }
    }
    for (run = 0; run < 12; run++) { /* byte by byte, all at once, then 10 random splittings */
        run_decoder(wire, len, run == 0 ? BYTE_BY_BYTE : run == 1 ? ALL_AT_ONCE : RANDOM_SPLITS,
                    0x9E3779B9u * (run + 1u), &got, name);
        if (got.n != want.n || memcmp(got.ev, want.ev, want.n * sizeof(event)) != 0) {
            printf("FAIL %s (run %u): events differ; got", name, run);
            for (k = 0; k < got.n; k++) {
                if (got.ev[k].kind == 'X')
                    printf(" X %s", cav_drop_reason_name(got.ev[k].reason));
                else
                    printf(" P %u %u %lu", got.ev[k].type, got.ev[k].seq, (unsigned long)got.ev[k].value);
            }
            printf("\n");
            failures++;
            return;
        }
        if (got.missed != want.missed || got.repeated != want.repeated) {
            fail(name, "missed/repeated counts differ");
            return;
        }
    }
}

/* ---------------------------------------------------------------- edge cases not in the file */

static void expect(int ok, const char *what)
{
    if (!ok)
        fail("builtin", what);
}

static void builtin_checks(void)
{
    static const uint8_t digits[] = "123456789";
    uint8_t out[CAV_MAX_ENCODED_BYTES], in[300];
    uint16_t samples[2100] = {0};
    cav_row row;
    cav_info info;
    cav_cmd_decoder d;
    cav_command c;
    size_t i;

    expect(cav_crc16(0xFFFF, digits, 9) == 0x29B1, "CRC-16/CCITT-FALSE check value");
    expect(cav_crc32(0, digits, 9) == 0xCBF43926u, "CRC-32 check value");
    expect(cav_crc32(cav_crc32(0, digits, 4), digits + 4, 5) == 0xCBF43926u, "CRC-32 in two calls");

    expect(cav_cobs_encode(in, 0, out, 1) == 1 && out[0] == 0x01, "COBS of nothing");
    in[0] = 0;
    expect(cav_cobs_encode(in, 1, out, 2) == 2 && out[0] == 1 && out[1] == 1, "COBS of 00");
    for (i = 0; i < 254; i++)
        in[i] = (uint8_t)(i % 255 + 1);
    expect(cav_cobs_encode(in, 254, out, 256) == 256 && out[0] == 0xFF && out[255] == 0x01, "COBS of 254 bytes");
    expect(cav_cobs_encode(in, 254, out, 255) == CAV_ERR_SPACE, "COBS into a short buffer");

    memset(&row, 0, sizeof row);
    row.samples = samples;
    row.count = 1;
    expect(cav_encode_row(out, sizeof out, 0, NULL) == CAV_ERR_ARG, "ROW: NULL row");
    row.packing = 3;
    expect(cav_encode_row(out, sizeof out, 0, &row) == CAV_ERR_ARG, "ROW: unknown packing");
    row.packing = CAV_PACKING_U8;
    samples[0] = 256;
    expect(cav_encode_row(out, sizeof out, 0, &row) == CAV_ERR_ARG, "ROW: 256 in u8");
    row.packing = CAV_PACKING_PACKED12;
    samples[0] = 4096;
    expect(cav_encode_row(out, sizeof out, 0, &row) == CAV_ERR_ARG, "ROW: 4096 in packed12");
    samples[0] = 4095;
    expect(cav_encode_row(out, sizeof out, 0, &row) > 0, "ROW: 4095 in packed12");
    row.samples = NULL;
    expect(cav_encode_row(out, sizeof out, 0, &row) == CAV_ERR_ARG, "ROW: NULL samples");
    row.samples = samples;
    row.packing = CAV_PACKING_U16;
    row.count = (CAV_MAX_PACKET_BYTES - CAV_ROW_BODY_BYTES - CAV_CRC_BYTES) / 2;
    expect(cav_encode_row(out, sizeof out, 0, &row) > 0, "ROW: largest u16 row");
    row.count++;
    expect(cav_encode_row(out, sizeof out, 0, &row) == CAV_ERR_ARG, "ROW: one sample past max_packet_bytes");
    expect(cav_encode_row(NULL, 0, 0, &row) == CAV_ERR_ARG, "ROW: too long beats no buffer");
    row.count = 1;
    expect(cav_encode_row(NULL, 0, 0, &row) == CAV_ERR_SPACE, "ROW: no buffer");

    memset(&info, 0, sizeof info);
    info.sign = 0;
    expect(cav_encode_info(out, sizeof out, 0, &info) == CAV_ERR_ARG, "INFO: sign 0");
    info.sign = CAV_SIGN_INCREASES;
    info.packing = 3;
    expect(cav_encode_info(out, sizeof out, 0, &info) == CAV_ERR_ARG, "INFO: unknown packing");
    expect(cav_encode_info(out, sizeof out, 0, NULL) == CAV_ERR_ARG, "INFO: NULL");
    expect(cav_encode_status(out, sizeof out, 0, NULL) == CAV_ERR_ARG, "STATUS: NULL");
    expect(cav_encode_frame_end(out, sizeof out, 0, NULL) == CAV_ERR_ARG, "FRAME_END: NULL");

    cav_cmd_decoder_init(&d);
    expect(cav_cmd_decoder_push(NULL, 1, &c) == CAV_RX_NONE && cav_cmd_decoder_push(&d, 1, NULL) == CAV_RX_NONE,
           "decoder: NULL arguments are ignored");
    expect(strcmp(cav_drop_reason_name(CAV_DROP_BAD_CRC), "bad_crc") == 0 &&
               strcmp(cav_drop_reason_name(999), "unknown") == 0,
           "drop reason names");
}

/* ---------------------------------------------------------------- main */

int main(int argc, char **argv)
{
    static char line[MAX_LINE];
    static char *tok[MAX_TOKENS];
    static packet_args args;
    int emit_only = argc > 1 && !strcmp(argv[1], "--emit");
    unsigned long n_enc = 0, n_dec = 0, n_crc = 0;

    if (!emit_only)
        builtin_checks();
    while (fgets(line, sizeof line, stdin) != NULL) {
        int nt = 0;
        char *p;
        if (strchr(line, '\n') == NULL && !feof(stdin)) {
            fprintf(stderr, "line too long\n");
            return 2;
        }
        if ((p = strtok(line, " \n")) == NULL)
            continue;
        while ((p = strtok(NULL, " \n")) != NULL && nt < MAX_TOKENS)
            tok[nt++] = p;
        if (line[0] == 'E' && nt >= 4) {
            parse_packet(tok + 1, nt - 2, &args);
            if (emit_only)
                emit(tok[0], &args);
            else
                check_encode(tok[0], &args, tok[nt - 1]);
            n_enc++;
        } else if (line[0] == 'F' && !emit_only && nt >= 3) {
            check_frame_crc(tok, nt);
            n_crc++;
        } else if (line[0] == 'D' && !emit_only && nt >= 5) {
            check_decode(tok, nt);
            n_dec++;
        } else if (!emit_only) {
            fprintf(stderr, "unreadable line starting %s\n", line);
            return 2;
        }
    }
    if (!emit_only)
        printf("%lu encoder, %lu frame CRC, %lu decoder vectors; %d failures\n", n_enc, n_crc, n_dec, failures);
    return failures ? 1 : 0;
}
