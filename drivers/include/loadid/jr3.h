/*
 * loadid drivers: the JR3 force-torque sensor (with accelerometer) on CAN,
 * the layout of docs/INTERFACE.md "JR3 over CAN" (proto/jr3.dbc describes the same).
 * Pure code: no I/O, no clock; frames in, samples out.
 *
 * Classic CAN 2.0A, 11-bit identifiers, DLC 8. One sample is four frames
 * with the same sequence number:
 *
 *   base+0  force f                 [N]        group LOADID_JR3_FORCE
 *   base+1  moment tau              [N m]      group LOADID_JR3_MOMENT
 *   base+2  linear: a - g of S      [m/s^2]    group LOADID_JR3_LINEAR
 *   base+3  angular acceleration    [rad/s^2]  group LOADID_JR3_ANGULAR
 *
 *   bytes 0-5: three little-endian int16 counts X, Y, Z;
 *   byte 6: sequence number (uint8, wraps); byte 7: status, bit 0 = a channel
 *   of this group saturated, bit 1 = sensor fault, bits 2-7 = 0.
 *   value = counts * full_scale / 16384.
 *
 *   base+4  (about once a second) byte 0 = group 0..3, byte 1 = 0, bytes
 *   2-7 = three little-endian uint16 full scales in units of 0.1 N,
 *   0.01 N m, 0.01 m/s^2, 0.1 rad/s^2 for groups 0..3; overrides the
 *   configured full scales of that group.
 *
 * Two halves:
 *   - the encoder (the simulator's side): SI values -> four frames, and the
 *     base+4 frame of a group;
 *   - the decoder (the daemon's side): a state machine fed one frame at a
 *     time that assembles samples and counts everything status_t reports.
 *
 * Return convention (loadid/error_text.h): 0 or a positive result code on success, a
 * negated errno or a LOADID_JR3_E_* code (all below -1000) otherwise;
 * loadid_jr3_strerror() names each.
 */
#ifndef LOADID_JR3_H
#define LOADID_JR3_H

#include <stdbool.h>
#include <stdint.h>

#include "loadid/can_frame.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_JR3_DEFAULT_BASE_ID 0x1A0u /* can.base_id */
#define LOADID_JR3_MAX_BASE_ID 0x7FBu     /* base+4 must stay an 11-bit id */
#define LOADID_JR3_NUM_GROUPS 4
#define LOADID_JR3_NUM_FRAMES 5                  /* base+0 .. base+4 */
#define LOADID_JR3_COUNTS_PER_FULL_SCALE 16384.0 /* value = counts * fs / 16384 */

/* Groups: index into the [4][3] arrays below, and id offset from base. */
enum loadid_jr3_group {
    LOADID_JR3_FORCE = 0,  /* f [N] */
    LOADID_JR3_MOMENT = 1, /* tau [N m] */
    LOADID_JR3_LINEAR = 2, /* a - g of the origin of S [m/s^2] */
    LOADID_JR3_ANGULAR = 3 /* alpha [rad/s^2] */
};
#define LOADID_JR3_FULL_SCALE_OFFSET 4 /* base+4: the full-scale frame */

/* Status byte (byte 7 of base+0..3). */
#define LOADID_JR3_STATUS_SATURATED 0x01u /* a channel of this group saturated */
#define LOADID_JR3_STATUS_FAULT 0x02u     /* sensor fault: discard the sample */
#define LOADID_JR3_STATUS_RESERVED 0xFCu  /* must be 0 */

/* Mask of all four groups, for loadid_jr3_encode's fault_groups. */
#define LOADID_JR3_ALL_GROUPS 0x0Fu

/* Results of loadid_jr3_decoder_feed (non-negative). */
enum loadid_jr3_result {
    LOADID_JR3_NONE = 0,      /* frame taken; nothing to hand on */
    LOADID_JR3_SAMPLE = 1,    /* out->sample is a complete, usable sample:
                                   the ONLY result after which a sample may
                                   go to an estimator */
    LOADID_JR3_FULL_SCALE = 2 /* a base+4 frame changed a group's full
                                   scale: out->full_scale says which (log it) */
};

/* Errors (negative). The first two are complete samples that must not be
 * used: out->sample holds them, flagged, for logging only. */
enum loadid_jr3_error {
    LOADID_JR3_E_SATURATED = -1101,  /* complete sample, a group saturated */
    LOADID_JR3_E_FAULT = -1102,      /* complete sample, sensor fault (wins
                                        over E_SATURATED when both) */
    LOADID_JR3_E_UNKNOWN_ID = -1103, /* id outside base..base+4, or extended */
    LOADID_JR3_E_DLC = -1104,        /* DLC is not 8 */
    LOADID_JR3_E_MALFORMED = -1105,  /* base+4 with group > 3, byte 1 != 0 or
                                        a zero full scale */
    LOADID_JR3_E_RESERVED = -1106,   /* status bits 2-7 set */
    LOADID_JR3_E_DUPLICATE = -1107,  /* a second frame of a group for the same
                                        sequence number (not a bad frame: the
                                        sample is abandoned or was complete) */
    LOADID_JR3_E_RANGE = -1108       /* encoder: a full scale that base+4
                                        cannot carry (rounds to 0 or > 65535
                                        units) */
};

/* Configuration (immutable after create). */
typedef struct {
    uint32_t base_id; /* can.base_id; default 0x1A0; <= 0x7FB */
    double full_scale[LOADID_JR3_NUM_GROUPS][3];
    /* jr3.full_scale.{force,moment,linear,angular}, X Y Z; > 0 and finite.
     * Defaults (the paper's 85M35A3-I40-D 200N12): 200 N, 12 N m,
     * 98.1 m/s^2, 1000 rad/s^2. */
} loadid_jr3_config_t;

/* One decoded sample. */
typedef struct {
    int64_t t_us;                             /* receive time of its base+0 frame [us] */
    uint8_t sequence;                         /* byte 6 of its frames */
    uint8_t status[LOADID_JR3_NUM_GROUPS];    /* byte 7 of each group's frame */
    bool saturated;                           /* bit 0 in some group */
    bool faulty;                              /* bit 1 in some group */
    int16_t counts[LOADID_JR3_NUM_GROUPS][3]; /* raw counts X Y Z */
    double value[LOADID_JR3_NUM_GROUPS][3];
    /* SI: counts * full_scale / 16384 with the full scale in force when the
     * group's frame arrived: [FORCE] N, [MOMENT] N m, [LINEAR] m/s^2,
     * [ANGULAR] rad/s^2 */
} loadid_jr3_sample_t;

/* A full-scale change made by a base+4 frame. */
typedef struct {
    int group;          /* enum loadid_jr3_group */
    double previous[3]; /* X Y Z before [SI] */
    double current[3];  /* X Y Z now in force [SI] */
    int64_t t_us;       /* receive time of the base+4 frame */
} loadid_jr3_full_scale_change_t;

/* What loadid_jr3_decoder_feed hands back; which member it wrote depends on
 * the return value (see there). */
typedef struct {
    loadid_jr3_sample_t sample;
    loadid_jr3_full_scale_change_t full_scale;
} loadid_jr3_output_t;

/* Counters since create or reset. status_t (docs/INTERFACE.md) takes samples_ok,
 * frames_bad, samples_incomplete, samples_saturated and sequence_gaps
 * directly. Invariants (checked by the tests):
 *   frames_total = frames_bad + frames_sample + frames_duplicate
 *                  + frames_discarded + full_scale_frames
 *   frames_bad = frames_unknown_id + frames_bad_dlc + frames_malformed
 *                + frames_reserved
 *   samples_started = samples_ok + samples_rejected + samples_incomplete
 *                     + (1 while a sample is being assembled)
 *   max(saturated, faulty) <= samples_rejected <= saturated + faulty */
typedef struct {
    int64_t frames_total;       /* every frame fed */
    int64_t frames_bad;         /* status_t.frames_bad: the four below */
    int64_t frames_unknown_id;  /* id outside base..base+4, or extended */
    int64_t frames_bad_dlc;     /* DLC != 8 */
    int64_t frames_malformed;   /* base+4: group > 3, byte 1 != 0, zero fs */
    int64_t frames_reserved;    /* base+0..3 with status bits 2-7 set */
    int64_t frames_sample;      /* data frames taken into a sample */
    int64_t frames_duplicate;   /* a group's frame again for one sequence */
    int64_t frames_discarded;   /* later frames of a sample abandoned after
                                   a duplicate */
    int64_t full_scale_frames;  /* valid base+4 frames */
    int64_t full_scale_changes; /* ... that changed the full scale */
    int64_t samples_started;    /* sequence numbers begun */
    int64_t samples_ok;         /* complete and usable (LOADID_JR3_SAMPLE) */
    int64_t samples_rejected;   /* complete, saturated or faulty or both */
    int64_t samples_saturated;  /* complete, status bit 0 in some group */
    int64_t samples_faulty;     /* complete, status bit 1 in some group */
    int64_t samples_incomplete; /* abandoned: a frame of another sequence
                                   number came first, or a duplicate */
    int64_t sequence_gaps;      /* sequence numbers skipped between two
                                   consecutive samples begun, mod 256 */
} loadid_jr3_stats_t;

typedef struct loadid_jr3_decoder loadid_jr3_decoder_t; /* opaque */

/* Fills cfg with the defaults above. */
void loadid_jr3_config_default(loadid_jr3_config_t *cfg);

/* Returns 0 when cfg is usable, -EINVAL otherwise (NULL, base_id > 0x7FB,
 * a full scale not finite or <= 0). */
int loadid_jr3_config_check(const loadid_jr3_config_t *cfg);

/* ---- Encoder ----------------------------------------------------------- */

/* The four frames base+0..3 of one sample: counts = round(value * 16384 /
 * full_scale) (half away from zero); a count outside int16 is clamped to
 * -32768 or 32767 and sets bit 0 (saturated) in its group's status; bit
 * g of fault_groups sets bit 1 (fault) in group g's status
 * (LOADID_JR3_ALL_GROUPS for a sensor fault). Every frame gets sequence,
 * t_us, DLC 8 and an 11-bit id.
 * Returns the mask of saturated groups (bit g = group g, 0..15);
 * -EINVAL for NULL arguments, an invalid cfg, a NaN value or fault_groups
 * above 15 (frames unchanged then). +-Inf saturates. */
int loadid_jr3_encode(const loadid_jr3_config_t *cfg, const double value[LOADID_JR3_NUM_GROUPS][3],
                      uint8_t sequence, unsigned fault_groups, int64_t t_us,
                      loadid_can_frame_t frames[LOADID_JR3_NUM_GROUPS]);

/* The base+4 frame announcing the full scales of one group: units
 * round(full_scale / unit) with unit 0.1 N, 0.01 N m, 0.01 m/s^2,
 * 0.1 rad/s^2 for groups 0..3. When sent is not NULL it receives the full
 * scales the frame actually carries (units * unit), which a decoder will
 * apply. Returns 0; -EINVAL for NULL frame or fs, base_id > 0x7FB, a group
 * outside 0..3 or a non-finite full scale; LOADID_JR3_E_RANGE when a full
 * scale rounds to 0 or above 65535 units. */
int loadid_jr3_encode_full_scale(uint32_t base_id, int group, const double fs[3], int64_t t_us,
                                 loadid_can_frame_t *frame, double sent[3]);

/* ---- Decoder ----------------------------------------------------------- */

/* Allocates a decoder for cfg (copied), with its full scales. The only
 * allocation. Returns 0; -EINVAL (NULL, invalid cfg), -ENOMEM. */
int loadid_jr3_decoder_create(const loadid_jr3_config_t *cfg, loadid_jr3_decoder_t **out);

/* Frees it; NULL is allowed. */
void loadid_jr3_decoder_destroy(loadid_jr3_decoder_t *dec);

/* Forgets the sample being assembled, the sequence history and every
 * counter, and goes back to the configured full scales. */
void loadid_jr3_decoder_reset(loadid_jr3_decoder_t *dec);

/* Feeds one frame (any frame from the bus: the decoder sorts them).
 * Sample assembly: a data frame (base+0..3) of a sequence number other
 * than the one being assembled abandons that sample (samples_incomplete)
 * and begins a new one (sequence_gaps += numbers skipped since the last one
 * begun, mod 256: 255 -> 0 is no gap); a sample is complete when its four
 * groups have arrived, in any order; a second frame of a group already
 * received abandons the sample (or, once complete, is just counted) and
 * every further frame of that sequence number is discarded. A frame with a
 * bad id, DLC or status is dropped before all that (and so leaves its
 * sample incomplete).
 *
 * Returns, with what it wrote into *out:
 *   LOADID_JR3_SAMPLE       out->sample: complete and usable.
 *   LOADID_JR3_NONE         nothing (frame taken, duplicate base+4 full
 *                           scale, frame discarded).
 *   LOADID_JR3_FULL_SCALE   out->full_scale: a group's full scale changed
 *                           (frames of that group from now on use it).
 *   LOADID_JR3_E_SATURATED, LOADID_JR3_E_FAULT
 *                           out->sample: complete but NOT usable, for
 *                           logging only.
 *   LOADID_JR3_E_DUPLICATE  nothing; counted (see above).
 *   LOADID_JR3_E_UNKNOWN_ID, _E_DLC, _E_MALFORMED, _E_RESERVED
 *                           nothing; the frame is dropped and counted in
 *                           frames_bad.
 *   -EINVAL                 NULL argument; nothing counted.
 * Allocation-free, constant time. */
int loadid_jr3_decoder_feed(loadid_jr3_decoder_t *dec, const loadid_can_frame_t *frame,
                            loadid_jr3_output_t *out);

/* Copies the counters. Returns 0, -EINVAL for NULL. */
int loadid_jr3_decoder_stats(const loadid_jr3_decoder_t *dec, loadid_jr3_stats_t *out);

/* Copies the full scales in force [SI] (configured, or from base+4).
 * Returns 0, -EINVAL for NULL. */
int loadid_jr3_decoder_full_scale(const loadid_jr3_decoder_t *dec,
                                  double out[LOADID_JR3_NUM_GROUPS][3]);

/* A static text for any return code of this module (or a negated errno).
 * Never NULL. */
const char *loadid_jr3_strerror(int code);

/* Group name: "force", "moment", "linear", "angular" (else "?"). */
const char *loadid_jr3_group_name(int group);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_JR3_H */
