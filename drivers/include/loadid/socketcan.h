/*
 * SocketCAN input (Linux CAN_RAW): one non-blocking raw socket on an
 * interface (can0 on a controller, vcan0 in tests), kernel filters for the
 * JR3's identifiers base..base+4 and for error frames, and the kernel's
 * receive time stamp of every frame (SO_TIMESTAMP).
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

/* Reads one frame. Returns 1 with *frame filled (t_us: the kernel's
 * receive time, microseconds since the epoch), 0 when nothing is waiting,
 * 2 for an error frame (a bus error reported by the controller; *frame
 * holds it), or -errno (-ENETDOWN, -ENODEV: the interface went away; reopen). */
int loadid_socketcan_read(int fd, loadid_can_frame_t *frame);

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
