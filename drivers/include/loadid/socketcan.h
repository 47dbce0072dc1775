/*
 * SocketCAN input (Linux CAN_RAW): one non-blocking raw socket on an
 * interface (can0 on a controller, vcan0 in tests), kernel filters for the
 * JR3's identifiers base..base+4 and for error frames, the kernel's
 * receive time stamp of every frame (SO_TIMESTAMP), and the count of
 * frames the kernel dropped because the socket's receive buffer was full
 * (SO_RXQ_OVFL, as candump reports them).
 */
#ifndef LOADID_SOCKETCAN_H
#define LOADID_SOCKETCAN_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/can_frame.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Opens the socket. Returns the file descriptor (>= 0), or -errno with a
 * one-line reason in err (no such interface, no CAN support, ...), with
 * what to do about the two common ones: -EAFNOSUPPORT (SocketCAN not
 * loaded: modprobe can_raw, vcan) and -ENODEV (no such interface: ip link
 * add ... type vcan). */
int loadid_socketcan_open(const char *ifname, uint32_t base_id, char *err, size_t errlen);

/* Reads one frame (one recvmsg). Returns 1 with *frame filled (t_us: the
 * kernel's receive time, microseconds since the epoch), 0 when nothing is
 * waiting, 2 for an error frame (a bus error reported by the controller;
 * *frame holds it), or -errno (-ENETDOWN, -ENODEV: the interface went
 * away; reopen). drops (may be NULL), on 1 or 2: the socket's cumulative
 * count of frames dropped for a full receive buffer, as of this frame's
 * queueing (SO_RXQ_OVFL); the kernel sends it only once it is non-zero, so
 * *drops is left as it was when the frame carries none. It wraps at 2^32
 * (take differences as uint32_t) and starts at 0 on every open. A drop is
 * learnt from the next frame queued after it. */
int loadid_socketcan_read(int fd, loadid_can_frame_t *frame, uint32_t *drops);

/* A socket for sending (no receive filter: it reads nothing). Returns the
 * file descriptor, or -errno with a reason in err. */
int loadid_socketcan_open_tx(const char *ifname, char *err, size_t errlen);

/* Sends one classic frame. Returns 0, -EAGAIN (the queue is full; retry),
 * or -errno. */
int loadid_socketcan_write(int fd, const loadid_can_frame_t *frame);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_SOCKETCAN_H */
