/*
 * Reads the chain from robot.base_link to robot.sensor_link out of a URDF
 * file (urdfdom). Host side: file access, XML and heap, at start-up only;
 * the per-sample code in the core never calls it.
 *
 * Accepted: revolute, continuous and prismatic joints (movable) and fixed
 * joints (folded into the neighbouring transforms) on the path from
 * base_link down to sensor_link. Rejected, with a message naming the file
 * and the cause: a file that cannot be read or parsed, a link that is not
 * there, a base_link that is not an ancestor of sensor_link, a kinematic
 * loop (a link with two parents, which urdfdom 3.0 lets through by keeping
 * the last one, or no root link, which urdfdom refuses), a floating or
 * planar joint or a mimic joint on the path, no movable joint, more than
 * LOADID_MAX_JOINTS, a zero axis, a non-finite number.
 */
#ifndef LOADID_URDF_H
#define LOADID_URDF_H

#include <stddef.h>

#include "loadid/chain.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fills chain from the URDF at path. On failure writes a one-line reason
 * into err (errlen bytes, may be 0) and returns -ENOENT (cannot read),
 * LOADID_E_MODEL (not a usable chain) or -EINVAL (NULL argument). */
int loadid_urdf_load_file(const char *path, const char *base_link, const char *sensor_link,
                          loadid_chain_t *chain, char *err, size_t errlen);

/* The same from URDF text in memory (name is used in messages). */
int loadid_urdf_load_string(const char *xml, const char *name, const char *base_link,
                            const char *sensor_link, loadid_chain_t *chain, char *err,
                            size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_URDF_H */
