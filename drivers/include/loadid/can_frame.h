/*
 * loadid drivers: one classic CAN 2.0 frame with its receive time, the type
 * the SocketCAN reader, the candump log reader and writer, and the JR3
 * encoder and decoder exchange. Plain C11.
 */
#ifndef LOADID_CAN_FRAME_H
#define LOADID_CAN_FRAME_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_CAN_MAX_DLEN 8           /* classic CAN: at most 8 data bytes */
#define LOADID_CAN_SFF_MASK 0x7FFu      /* 11-bit identifier (CAN 2.0A) */
#define LOADID_CAN_EFF_MASK 0x1FFFFFFFu /* 29-bit identifier (CAN 2.0B) */

/* One classic CAN data frame. Remote, error and CAN FD frames have no
 * representation: the readers refuse them. */
typedef struct {
    uint32_t id;   /* identifier, without flag bits: <= 0x7FF, or
                          <= 0x1FFFFFFF when extended */
    uint8_t dlc;   /* number of data bytes, 0..8 (a larger value is a
                          malformed frame: data[] holds 8 bytes only) */
    bool extended; /* 29-bit identifier */
    uint8_t data[LOADID_CAN_MAX_DLEN];
    int64_t t_us; /* receive time [us since the Unix epoch] */
} loadid_can_frame_t;

#ifdef __cplusplus
}
#endif

#endif /* LOADID_CAN_FRAME_H */
