/*
 * A serial kinematic chain from the base frame to the sensor frame S, as
 * plain data: what a URDF says about the movable joints between
 * robot.base_link and robot.sensor_link (docs/INTERFACE.md), with every fixed joint
 * folded into the next transform. loadid/urdf.h fills it from a URDF file;
 * tests may fill it by hand. Doubles throughout: it is configuration, read
 * once, whatever scalar the core computes in.
 *
 * Frames follow URDF: joint i's frame is its parent frame moved by the
 * fixed transform (origin_xyz, origin_rot), then by the joint's motion
 * along or about `axis` (given in joint i's frame); the child link's frame
 * is the moved joint frame. After the last movable joint, (tip_xyz,
 * tip_rot) leads to S.
 */
#ifndef LOADID_CHAIN_H
#define LOADID_CHAIN_H

#include "loadid/types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LOADID_MAX_JOINTS 16 /* movable joints of one chain */
#define LOADID_NAME_MAX 64   /* link and joint names, with the NUL */

typedef enum {
    LOADID_JOINT_REVOLUTE = 1, /* URDF revolute and continuous [rad] */
    LOADID_JOINT_PRISMATIC = 2 /* URDF prismatic [m] */
} loadid_joint_type_t;

typedef struct {
    char name[LOADID_NAME_MAX];
    loadid_joint_type_t type;
    double origin_xyz[3]; /* parent frame -> joint frame [m] */
    double origin_rot[9]; /* its rotation, row-major; columns are the
                                     joint frame's axes in the parent frame */
    double axis[3];       /* unit vector in the joint frame */
    /* Limits from the URDF <limit> (position in rad or m, velocity in rad/s
     * or m/s); a continuous joint has lower = -inf, upper = +inf. A limit
     * the URDF does not give is +inf (velocity) or +-inf (position). */
    double lower, upper, velocity;
} loadid_joint_desc_t;

typedef struct {
    char base_link[LOADID_NAME_MAX];
    char sensor_link[LOADID_NAME_MAX];
    int num_joints;                                /* 1 .. LOADID_MAX_JOINTS */
    loadid_joint_desc_t joints[LOADID_MAX_JOINTS]; /* base to sensor order */
    double tip_xyz[3];                             /* last joint's child frame -> S [m] */
    double tip_rot[9];                             /* row-major, like origin_rot */
} loadid_chain_t;

/* Checks a chain for use: 1 .. LOADID_MAX_JOINTS joints, known types, unit
 * axes (within 1e-9), proper rotations (orthonormal within 1e-9, det +1),
 * everything finite, lower <= upper, velocity > 0.
 * Returns 0 or -EINVAL (a NULL chain or any of the above broken). */
int loadid_chain_check(const loadid_chain_t *chain);

#ifdef __cplusplus
}
#endif

#endif /* LOADID_CHAIN_H */
