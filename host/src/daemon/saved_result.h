/*
 * A finished estimate saved by loadidd (results.directory) and loaded at
 * start-up (results.load), so that wrench_t flows after a restart:
 *
 *   format: loadid-estimate-1
 *   method: RTLS
 *   load_name: "o1"
 *   utime: 1700000002499370
 *   samples: 1500
 *   phi: [10]  offset: [6]  mass: x  com: [3]  inertia_com: [6]
 *   condition_number: x
 *   physically_consistent: true
 *   compensation: {n_params: 10, phi_total: [n], zeroed: true, y0: [6], g_init: [3]}
 *   urdf_inertial: |          # the load as a URDF <inertial> element, frame S
 *     <inertial> ... </inertial>
 */
#ifndef LOADID_SAVED_RESULT_H
#define LOADID_SAVED_RESULT_H

#include <stddef.h>
#include <stdint.h>

#include "loadid/pipeline.h"

/* dir/<load_name or "load">-<utime><ext>, the load name's '/', '.' and
 * control characters made '_': the saved result's name (ext ".yaml"),
 * and its trace's (".trace.csv", trace_worker.h). */
void loadid_saved_result_name(const char *dir, const char *load_name, int64_t utime,
                              const char *ext, char *out, size_t len);

/* Writes dir/<load_name or "load">-<utime>.yaml and dir/latest.yaml
 * (created if missing), each through a .tmp file synced and renamed over
 * it. path (may be NULL) receives the first's name. Allocates nothing (no
 * stdio: a fixed buffer, open, write, fsync, rename), for loadidd's save
 * worker calls it (save_worker.h: it waits for the disk, so never on the
 * loop). Returns 0 or -errno (-EOVERFLOW: the document outgrew its buffer)
 * with a reason in err. */
int loadid_saved_result_write(const char *dir, const loadid_pipeline_estimate_t *est,
                              const loadid_pipeline_compensation_t *comp, char *path,
                              size_t pathlen, char *err, size_t errlen);

/* Reads one. Returns 0, or a negative code with "FILE:LINE: KEY: ..." in
 * err. */
int loadid_saved_result_read(const char *file, loadid_pipeline_estimate_t *est,
                             loadid_pipeline_compensation_t *comp, char *err, size_t errlen);

#endif /* LOADID_SAVED_RESULT_H */
