/* `loadid plot` (cli_plot.h). */
#define _POSIX_C_SOURCE 200809L

#include "cli_plot.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static int is_file(const char *dir, const char *name) {
    char p[PATH_MAX];
    struct stat st;
    return snprintf(p, sizeof p, "%s/%s", dir, name) < (int)sizeof p && stat(p, &st) == 0 &&
           S_ISREG(st.st_mode);
}

static int is_exec(const char *path) {
    return access(path, X_OK) == 0;
}

static int mkdir_p(const char *dir) {
    char buf[PATH_MAX];
    if (snprintf(buf, sizeof buf, "%s", dir) >= (int)sizeof buf) return -ENAMETOOLONG;
    for (char *p = buf + 1; *p; ++p)
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -errno;
            *p = '/';
        }
    if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -errno;
    return 0;
}

/* Runs argv (argv[0] a path) and waits. Returns its exit status, or -1. */
static int run(char *const argv[]) {
    fflush(stdout);
    const pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        execv(argv[0], argv);
        fprintf(stderr, "cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    int status;
    if (waitpid(pid, &status, 0) != pid) return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int loadid_cli_plot(const char *prog, const char *config, const char *path, const char *out,
                    int publish_every) {
    char here[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", here, sizeof here - 1);
    if (n <= 0) {
        fprintf(stderr, "%s: plot: cannot find this program's folder: %s\n", prog, strerror(errno));
        return 1;
    }
    here[n] = 0;
    *strrchr(here, '/') = 0;
    char script[PATH_MAX + 64], python[PATH_MAX + 64];
    snprintf(script, sizeof script, "%s/../share/loadid/loadid_plot.py", here);
    if (access(script, R_OK) != 0) {
        fprintf(stderr, "%s: plot: the drawing script is missing: %s\n", prog, script);
        return 1;
    }
    const char *env = getenv("LOADID_PYTHON");
    snprintf(python, sizeof python, "%s/../../venv/bin/python", here);
    if (env && *env)
        snprintf(python, sizeof python, "%s", env);
    else if (!is_exec(python))
        snprintf(python, sizeof python, "python3");

    struct stat st;
    if (stat(path, &st) != 0) {
        fprintf(stderr, "%s: plot: %s: %s\n", prog, path, strerror(errno));
        return 1;
    }
    const int recording =
        S_ISDIR(st.st_mode) && is_file(path, "can.log") && is_file(path, "lcm.log");
    char outdir[PATH_MAX], trace[PATH_MAX + 16], result[PATH_MAX + 16], truth[PATH_MAX + 16];
    char every[32];
    const char *args[16];
    int k = 0;
    args[k++] = python;
    args[k++] = script;
    if (recording) {
        if (!config) {
            fprintf(stderr,
                    "%s: plot: %s is a recording: give the configuration to estimate it "
                    "with (--config FILE)\n",
                    prog, path);
            return 2;
        }
        snprintf(outdir, sizeof outdir, "%s", out ? out : path);
        if (!out) strncat(outdir, "/plots", sizeof outdir - strlen(outdir) - 1);
        const int rc = mkdir_p(outdir);
        if (rc != 0) {
            fprintf(stderr, "%s: plot: cannot make %s: %s\n", prog, outdir, strerror(-rc));
            return 1;
        }
        char loadidd[PATH_MAX + 16];
        snprintf(loadidd, sizeof loadidd, "%s/loadidd", here);
        snprintf(trace, sizeof trace, "%s/trace.csv", outdir);
        snprintf(result, sizeof result, "%s/result.json", outdir);
        snprintf(every, sizeof every, "%d", publish_every);
        const char *d[16] = {loadidd,   "--config", config,     "--offline", path,
                             "--trace", trace,      "--result", result,      "--allow-incomplete"};
        int j = 10;
        if (publish_every > 0) d[j++] = "--publish-every", d[j++] = every;
        d[j] = NULL;
        printf("%s plot: loadidd --offline %s: the estimates in %s, their trace in %s\n", prog,
               path, result, trace);
        const int st_d = run((char *const *)d);
        if (st_d != 0) {
            fprintf(stderr, "%s: plot: loadidd --offline %s failed (exit %d)\n", prog, path, st_d);
            return 1;
        }
        if (is_file(path, "truth.yaml")) {
            snprintf(truth, sizeof truth, "%s/truth.yaml", path);
            args[k++] = "--truth";
            args[k++] = truth;
        }
        args[k++] = "--out";
        args[k++] = outdir;
        args[k++] = trace;
    } else {
        if (publish_every > 0) {
            fprintf(stderr, "%s: plot: --publish-every is for a recording; %s is drawn as it is\n",
                    prog, path);
            return 2;
        }
        if (out) args[k++] = "--out", args[k++] = out;
        args[k++] = path;
    }
    args[k] = NULL;
    fflush(stdout);
    execvp(args[0], (char *const *)args);
    fprintf(stderr,
            "%s: plot: cannot run %s: %s (LOADID_PYTHON names a Python with numpy and "
            "matplotlib)\n",
            prog, args[0], strerror(errno));
    return 1;
}
