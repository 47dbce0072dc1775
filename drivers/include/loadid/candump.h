/*
 * loadid drivers: the candump log format of can-utils (`candump -l`,
 * `canplayer -I`), one classic CAN frame a line (docs/INTERFACE.md, recordings):
 *
 *   (1700000000.123456) vcan0 1A0#0102030405060708
 *
 * `(seconds.microseconds)`, the interface name, then the frame: 3 hex digits
 * for an 11-bit identifier or 8 for a 29-bit one, `#`, and 0 to 8 data bytes
 * as hex pairs (can-utils also writes and reads an optional `.` between
 * bytes; accepted here, never written). The formatter writes what
 * `candump -l` writes: seconds zero-padded to 10 digits, upper-case hex.
 * Parsing is exact: the time goes to microseconds in integers, never
 * through a double.
 *
 * Not classic CAN data frames, so refused with their own codes: CAN FD
 * (`123##1...`, also CAN XL `###`) and remote frames (`123#R`, `123#R4`).
 *
 * Return convention (loadid/error_text.h): 0 or a count on success, a negated errno
 * or a LOADID_CANDUMP_E_* code (all below -1000) otherwise;
 * loadid_candump_strerror() names each.
 */
#ifndef LOADID_CANDUMP_H
#define LOADID_CANDUMP_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "loadid/can_frame.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_CANDUMP_IFNAME_MAX 16 /* IFNAMSIZ: at most 15 characters + NUL */
#define LOADID_CANDUMP_LINE_MAX \
    128 /* longest line the reader accepts, with
                                        its newline (a classic frame with a
                                        20-digit time needs about 70) */

enum loadid_candump_error {
    LOADID_CANDUMP_E_SYNTAX = -1501,    /* not "(time) ifname frame": missing
                                           field, separator, stray text */
    LOADID_CANDUMP_E_TIMESTAMP = -1502, /* not "(digits.6digits)", or beyond
                                           int64 microseconds */
    LOADID_CANDUMP_E_IFNAME = -1503,    /* empty, longer than 15, or a control
                                           character */
    LOADID_CANDUMP_E_ID = -1504,        /* not 3 or 8 hex digits, or above
                                           0x7FF / 0x1FFFFFFF (error frames) */
    LOADID_CANDUMP_E_DATA = -1505,      /* odd or non-hex digits, misplaced
                                           '.', more than 8 bytes */
    LOADID_CANDUMP_E_FD = -1506,        /* a CAN FD (or XL) frame: "##" */
    LOADID_CANDUMP_E_REMOTE = -1507,    /* a remote frame: "#R" */
    LOADID_CANDUMP_E_LONG_LINE = -1508  /* reader: line longer than
                                           LOADID_CANDUMP_LINE_MAX, or holding
                                           a NUL byte */
};

/* Writes the log line of frame (received on ifname) into buf with its
 * '\n' and a terminating NUL. Returns the length written without the NUL;
 * -EINVAL for NULL arguments, an invalid ifname, dlc > 8, an id too large
 * for its kind, or t_us < 0; -ENOSPC when size is too small (buf then holds
 * an empty string). */
int loadid_candump_format(const loadid_can_frame_t *frame, const char *ifname, char *buf,
                          size_t size);

/* Parses one line (a trailing "\n", "\r\n" or trailing blanks are
 * allowed). On success fills *frame (t_us from the time, extended from the
 * id's length) and, when ifname is not NULL, the interface name, and
 * returns 0. Otherwise returns -EINVAL (NULL line or frame) or a
 * LOADID_CANDUMP_E_* code, and *frame is unspecified. */
int loadid_candump_parse(const char *line, loadid_can_frame_t *frame,
                         char ifname[LOADID_CANDUMP_IFNAME_MAX]);

/* A static text for any return code of this module (or a negated errno).
 * Never NULL. */
const char *loadid_candump_strerror(int code);

/* ---- Reader over a FILE* ----------------------------------------------- */

typedef struct loadid_candump_reader loadid_candump_reader_t; /* opaque */

/* Allocates a reader of fp (which stays the caller's: closing the reader
 * does not close it). Returns 0; -EINVAL, -ENOMEM. */
int loadid_candump_reader_open(FILE *fp, loadid_candump_reader_t **out);

/* Frees it; NULL is allowed. */
void loadid_candump_reader_close(loadid_candump_reader_t *r);

/* Reads the next frame, skipping empty (blank) lines. Returns 1 with
 * *frame (and ifname when not NULL) filled; 0 at the end of the file;
 * a LOADID_CANDUMP_E_* code for a bad line, which is consumed, so reading
 * can go on with the next line; -EIO on a read error; -EINVAL for NULL
 * arguments. loadid_candump_reader_line() then gives the number of that
 * line. */
int loadid_candump_read(loadid_candump_reader_t *r, loadid_can_frame_t *frame,
                        char ifname[LOADID_CANDUMP_IFNAME_MAX]);

/* The number (from 1) of the line the last loadid_candump_read returned or
 * failed on; 0 before the first. */
long loadid_candump_reader_line(const loadid_candump_reader_t *r);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_CANDUMP_H */
