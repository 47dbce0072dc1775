/* Recording folder writer (recording_writer.h). */
#define _POSIX_C_SOURCE 200809L
#include "recording_writer.h"

#include <dirent.h>
#include <errno.h>
#include <lcm/eventlog.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "lcmtypes/loadid_command_t.h"
#include "lcmtypes/loadid_joint_state_t.h"
#include "loadid/candump.h"

struct loadid_recording_writer {
    FILE *can;
    lcm_eventlog_t *lcm;
    char ifname[32];
    int64_t eventnum;
    int failed; /* errno of the first write that failed */
    loadid_recording_counts_t counts;
};

int loadid_recording_dir_check(const char *dir, int force, const char *force_option, char *err,
                               size_t errlen) {
    struct stat st;
    if (stat(dir, &st) != 0) {
        if (errno == ENOENT) return 0;
        const int e = errno;
        snprintf(err, errlen, "%s: %s", dir, strerror(e));
        return -e;
    }
    if (!S_ISDIR(st.st_mode)) {
        snprintf(err, errlen, "%s: exists and is not a directory", dir);
        return -ENOTDIR;
    }
    if (force) return 0;
    DIR *d = opendir(dir);
    if (!d) {
        const int e = errno;
        snprintf(err, errlen, "%s: %s", dir, strerror(e));
        return -e;
    }
    const struct dirent *ent;
    char first[256] = "";
    while ((ent = readdir(d)))
        if (strcmp(ent->d_name, ".") != 0 && strcmp(ent->d_name, "..") != 0) {
            snprintf(first, sizeof first, "%s", ent->d_name);
            break;
        }
    closedir(d);
    if (!first[0]) return 0;
    snprintf(err, errlen,
             "%s: not empty (it holds %s): give another folder, or %s to write "
             "the recording into it",
             dir, first, force_option);
    return -EEXIST;
}

int loadid_recording_open(const char *dir, const char *ifname, loadid_recording_writer_t **out,
                          char *err, size_t errlen) {
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
        int e = errno;
        snprintf(err, errlen, "%s: cannot create: %s", dir, strerror(e));
        return -e;
    }
    loadid_recording_writer_t *w = calloc(1, sizeof *w);
    if (!w) return -ENOMEM;
    snprintf(w->ifname, sizeof w->ifname, "%s", ifname);
    char path[4200];
    snprintf(path, sizeof path, "%s/can.log", dir);
    w->can = fopen(path, "w");
    if (w->can) {
        snprintf(path, sizeof path, "%s/lcm.log", dir);
        w->lcm = lcm_eventlog_create(path, "w");
    }
    if (!w->can || !w->lcm) {
        int e = errno ? errno : EIO;
        snprintf(err, errlen, "%s: cannot write: %s", path, strerror(e));
        if (w->can) fclose(w->can);
        free(w);
        return -e;
    }
    *out = w;
    return 0;
}

int loadid_recording_can(loadid_recording_writer_t *w, const loadid_can_frame_t *frame) {
    char line[128];
    int n = loadid_candump_format(frame, w->ifname, line, sizeof line);
    if (n < 0) return n;
    if (fwrite(line, 1, (size_t)n, w->can) != (size_t)n && !w->failed)
        w->failed = errno ? errno : EIO;
    w->counts.can_frames++;
    return 0;
}

static int log_event(loadid_recording_writer_t *w, int64_t utime, const char *channel, void *data,
                     int len) {
    lcm_eventlog_event_t ev = {
        .eventnum = w->eventnum++,
        .timestamp = utime,
        .channellen = (int32_t)strlen(channel),
        .datalen = len,
        .channel = (char *)channel,
        .data = data,
    };
    if (lcm_eventlog_write_event(w->lcm, &ev) != 0 && !w->failed) w->failed = errno ? errno : EIO;
    return 0;
}

int loadid_recording_joints(loadid_recording_writer_t *w, int64_t utime, int num_joints,
                            const double *position, const double *setpoint) {
    loadid_joint_state_t msg = {
        .utime = utime,
        .num_joints = num_joints,
        .position = (double *)position,
        .setpoint = (double *)setpoint,
    };
    uint8_t buf[4096];
    int len = loadid_joint_state_t_encoded_size(&msg);
    if (len < 0 || len > (int)sizeof buf || loadid_joint_state_t_encode(buf, 0, len, &msg) != len)
        return -EINVAL;
    w->counts.joint_msgs++;
    return log_event(w, utime, "LOADID_JOINTS", buf, len);
}

int loadid_recording_command(loadid_recording_writer_t *w, int64_t utime, int action,
                             const char *load_name) {
    loadid_command_t msg = {
        .utime = utime, .action = (int8_t)action, .load_name = (char *)load_name};
    uint8_t buf[1024];
    int len = loadid_command_t_encoded_size(&msg);
    if (len < 0 || len > (int)sizeof buf || loadid_command_t_encode(buf, 0, len, &msg) != len)
        return -EINVAL;
    w->counts.commands++;
    return log_event(w, utime, "LOADID_COMMAND", buf, len);
}

void loadid_recording_counts(const loadid_recording_writer_t *w, loadid_recording_counts_t *c) {
    *c = w->counts;
}

int loadid_recording_close(loadid_recording_writer_t *w) {
    if (!w) return 0;
    int e = w->failed;
    if (fclose(w->can) != 0 && !e) e = errno ? errno : EIO;
    lcm_eventlog_destroy(w->lcm);
    free(w);
    return -e;
}
