/*
 * jr3_decode_log: the project's candump reader and JR3 decoder over a
 * can.log, for the Python tests of recordings (tests/python/
 * test_sim_recording.py). Default JR3 configuration (base 0x1A0, default
 * full scales). Writes one line per event:
 *   S rc t_us sequence v0 .. v11   a complete sample (rc 1 usable, or the
 *                                  saturated / fault code), values in SI
 *   B line code                    a line that is not a frame
 *   T name value                   at the end: every decoder counter
 * Exit 0, or 1 when the file cannot be read.
 */
#include <stdio.h>
#include <string.h>

#include "loadid/candump.h"
#include "loadid/jr3.h"

int main(int argc, char **argv) {
    if (argc == 2 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printf(
            "usage: jr3_decode_log CAN.LOG\n"
            "Decodes a candump log's JR3 frames (base 0x1A0, default full scales): one\n"
            "line per complete sample (S), per line that is not a frame (B), and the\n"
            "decoder's counters at the end (T).\n");
        return 0;
    }
    if (argc != 2) {
        fprintf(stderr, "usage: jr3_decode_log CAN.LOG\n");
        return 1;
    }
    FILE *f = fopen(argv[1], "r");
    loadid_candump_reader_t *r = NULL;
    loadid_jr3_config_t cfg;
    loadid_jr3_config_default(&cfg);
    loadid_jr3_decoder_t *dec = NULL;
    if (!f || loadid_candump_reader_open(f, &r) != 0 ||
        loadid_jr3_decoder_create(&cfg, &dec) != 0) {
        fprintf(stderr, "jr3_decode_log: cannot read %s\n", argv[1]);
        return 1;
    }
    loadid_can_frame_t frame;
    int rc;
    while ((rc = loadid_candump_read(r, &frame, NULL)) != 0) {
        if (rc == -5 /* -EIO */) return 1;
        if (rc < 0) {
            printf("B %ld %d\n", loadid_candump_reader_line(r), rc);
            continue;
        }
        loadid_jr3_output_t out;
        int res = loadid_jr3_decoder_feed(dec, &frame, &out);
        if (res == LOADID_JR3_SAMPLE || res == LOADID_JR3_E_SATURATED ||
            res == LOADID_JR3_E_FAULT) {
            printf("S %d %lld %u", res, (long long)out.sample.t_us, (unsigned)out.sample.sequence);
            for (int g = 0; g < 4; ++g)
                for (int i = 0; i < 3; ++i) printf(" %.17g", out.sample.value[g][i]);
            printf("\n");
        }
    }
    loadid_jr3_stats_t s;
    loadid_jr3_decoder_stats(dec, &s);
#define STAT(x) printf("T " #x " %lld\n", (long long)s.x)
    STAT(frames_total);
    STAT(frames_bad);
    STAT(frames_unknown_id);
    STAT(frames_bad_dlc);
    STAT(frames_malformed);
    STAT(frames_reserved);
    STAT(frames_sample);
    STAT(frames_duplicate);
    STAT(frames_discarded);
    STAT(full_scale_frames);
    STAT(full_scale_changes);
    STAT(samples_started);
    STAT(samples_ok);
    STAT(samples_rejected);
    STAT(samples_saturated);
    STAT(samples_faulty);
    STAT(samples_incomplete);
    STAT(sequence_gaps);
    loadid_jr3_decoder_destroy(dec);
    loadid_candump_reader_close(r);
    fclose(f);
    return 0;
}
