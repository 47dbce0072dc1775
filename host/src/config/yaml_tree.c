/*
 * The YAML document tree (yaml_tree.h): libyaml's event API builds nodes
 * with their lines; the typed conversions and the error messages are ours.
 *
 * The event API rather than libyaml's document API: it lets the builder
 * refuse duplicate keys, aliases and deep nesting as they come, with the
 * line and the path of the node being built, and name that path in a
 * syntax error too (the document API stops with only a mark).
 */
#define _POSIX_C_SOURCE 200809L

#include "loadid/yaml_tree.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

struct loadid_yaml_node {
    loadid_yaml_kind_t kind;
    int line;                      /* 1-based */
    int used;                      /* a mapping value asked for by a reader */
    int plain;                     /* scalar: plain style and no !!str tag */
    char *text;                    /* scalar: value, NUL-terminated */
    size_t length;                 /* scalar: bytes in text */
    loadid_yaml_node_t **child;    /* sequence: items; mapping: k0, v0, k1, v1... */
    size_t count, cap;             /* pointers in child */
    loadid_yaml_node_t *parent;    /* NULL for the root */
    const loadid_yaml_node_t *key; /* in a mapping (key and value): the key */
    size_t index;                  /* in a sequence: the item's index */
    char **asked;                  /* mapping: every key a reader looked up,
                                     present or not (for "did you mean") */
    size_t n_asked, cap_asked;
    loadid_yaml_doc_t *doc;
};

struct loadid_yaml_doc {
    char *file;
    loadid_yaml_node_t *root;
    loadid_yaml_node_t **all; /* every node, for freeing without recursion */
    size_t n_all, cap_all;
    char error[1024];
};

static const char kTopLevel[] = "(top level)";

/* --- Messages ------------------------------------------------------------- */

/* One line: control characters (a newline in a key or a quoted value)
 * become '?'. */
static void one_line(char *s) {
    for (; *s; ++s)
        if ((unsigned char)*s < 0x20 || *s == 0x7f) *s = '?';
}

static void vformat_at(loadid_yaml_doc_t *doc, int line, const char *path, const char *fmt,
                       va_list ap) {
    int n = snprintf(doc->error, sizeof doc->error, "%s:%d: %s: ", doc->file, line, path);
    if (n >= 0 && (size_t)n < sizeof doc->error)
        vsnprintf(doc->error + n, sizeof doc->error - (size_t)n, fmt, ap);
    one_line(doc->error);
}

static int fail_line(loadid_yaml_doc_t *doc, int line, const char *path, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static int fail_line(loadid_yaml_doc_t *doc, int line, const char *path, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vformat_at(doc, line, path, fmt, ap);
    va_end(ap);
    return -EINVAL;
}

int loadid_yaml_fail(const loadid_yaml_node_t *node, const char *fmt, ...) {
    char path[512];
    loadid_yaml_path(node, path, sizeof path);
    va_list ap;
    va_start(ap, fmt);
    vformat_at(node->doc, node->line, path, fmt, ap);
    va_end(ap);
    return -EINVAL;
}

static int out_of_memory(loadid_yaml_doc_t *doc) {
    snprintf(doc->error, sizeof doc->error, "%s: out of memory", doc->file);
    return -ENOMEM;
}

static int is_null_scalar(const loadid_yaml_node_t *n) {
    if (n->kind != LOADID_YAML_SCALAR || !n->plain) return 0;
    static const char *const kNull[] = {"", "~", "null", "Null", "NULL"};
    for (size_t i = 0; i < sizeof kNull / sizeof kNull[0]; ++i)
        if (n->length == strlen(kNull[i]) && !memcmp(n->text, kNull[i], n->length)) return 1;
    return 0;
}

/* "a mapping", "null", "'abc'", "the string \"1.5\"": what a node is, for
 * "expected X, got Y"; long values are cut at 40 characters. */
static const char *describe(const loadid_yaml_node_t *n, char *buf, size_t len) {
    if (n->kind == LOADID_YAML_MAPPING) return "a mapping";
    if (n->kind == LOADID_YAML_SEQUENCE) return "a sequence";
    if (is_null_scalar(n)) return "null";
    const int cut = n->length > 40;
    const int shown = cut ? 40 : (int)n->length;
    if (n->plain)
        snprintf(buf, len, "'%.*s%s'", shown, n->text, cut ? "..." : "");
    else
        snprintf(buf, len, "the string \"%.*s%s\"", shown, n->text, cut ? "..." : "");
    return buf;
}

/* --- Paths ---------------------------------------------------------------- */

static void put(char *buf, size_t len, size_t *pos, const char *s, size_t n) {
    for (size_t i = 0; i < n; ++i, ++*pos)
        if (*pos + 1 < len) buf[*pos] = s[i] ? s[i] : '?';
}

static void path_append(const loadid_yaml_node_t *n, char *buf, size_t len, size_t *pos) {
    const loadid_yaml_node_t *p = n->parent;
    if (!p) return;
    path_append(p, buf, len, pos); /* depth <= LOADID_YAML_MAX_DEPTH */
    if (p->kind == LOADID_YAML_MAPPING) {
        if (*pos > 0) put(buf, len, pos, ".", 1);
        put(buf, len, pos, n->key->text, n->key->length);
    } else {
        char idx[32];
        const int k = snprintf(idx, sizeof idx, "[%zu]", n->index);
        put(buf, len, pos, idx, (size_t)k);
    }
}

size_t loadid_yaml_path(const loadid_yaml_node_t *node, char *buf, size_t len) {
    size_t pos = 0;
    if (node) path_append(node, buf, len, &pos);
    if (pos == 0) put(buf, len, &pos, kTopLevel, sizeof kTopLevel - 1);
    if (len > 0) buf[pos < len ? pos : len - 1] = '\0';
    return pos;
}

/* --- Building ------------------------------------------------------------- */

/* array with room for need elements of elem bytes (array itself when it
 * has it; *cap is its capacity), or NULL when out of memory (array is then
 * unchanged). */
static void *grow(void *array, size_t *cap, size_t need, size_t elem) {
    if (need <= *cap) return array;
    size_t n = *cap ? *cap * 2 : 8;
    while (n < need) n *= 2;
    if (n > SIZE_MAX / elem) return NULL;
    void *p = realloc(array, n * elem);
    if (p) *cap = n;
    return p;
}

static int clamp_line(size_t zero_based) {
    return zero_based >= (size_t)INT_MAX ? INT_MAX : (int)zero_based + 1;
}

static loadid_yaml_node_t *new_node(loadid_yaml_doc_t *doc, loadid_yaml_kind_t kind,
                                    const yaml_mark_t *mark) {
    void *all = grow(doc->all, &doc->cap_all, doc->n_all + 1, sizeof *doc->all);
    if (!all) return NULL;
    doc->all = all;
    loadid_yaml_node_t *n = calloc(1, sizeof *n);
    if (!n) return NULL;
    n->kind = kind;
    n->line = clamp_line(mark->line);
    n->doc = doc;
    doc->all[doc->n_all++] = n;
    return n;
}

static int push_child(loadid_yaml_node_t *parent, loadid_yaml_node_t *child) {
    void *room = grow(parent->child, &parent->cap, parent->count + 1, sizeof *parent->child);
    if (!room) return -ENOMEM;
    parent->child = room;
    parent->child[parent->count++] = child;
    return 0;
}

static int same_text(const loadid_yaml_node_t *a, const char *s, size_t len) {
    return a->length == len && !memcmp(a->text, s, len);
}

/* Hangs node under the innermost open collection (or makes it the root). */
static int attach(loadid_yaml_doc_t *doc, loadid_yaml_node_t **stack, int depth,
                  loadid_yaml_node_t *node) {
    if (depth == 0) {
        doc->root = node;
        return 0;
    }
    loadid_yaml_node_t *p = stack[depth - 1];
    node->parent = p;
    if (p->kind == LOADID_YAML_SEQUENCE) {
        node->index = p->count;
    } else if (p->count % 2 == 0) { /* a key */
        if (node->kind != LOADID_YAML_SCALAR) {
            char path[512];
            loadid_yaml_path(p, path, sizeof path);
            return fail_line(doc, node->line, path, "a key must be a scalar, not %s",
                             node->kind == LOADID_YAML_MAPPING ? "a mapping" : "a sequence");
        }
        node->key = node;
        for (size_t i = 0; i < p->count; i += 2) {
            if (same_text(p->child[i], node->text, node->length))
                return loadid_yaml_fail(node, "duplicate key (first on line %d)",
                                        p->child[i]->line);
        }
    } else { /* the value of the pending key */
        node->key = p->child[p->count - 1];
    }
    return push_child(p, node) ? out_of_memory(doc) : 0;
}

/* Where the parser is, for errors that have no node of their own: the
 * pending key of the innermost open mapping, or the innermost open
 * collection; with next_item, the next item of an open sequence (an alias
 * is an item; a syntax error there, e.g. a missing ']', is the
 * sequence's). */
static void current_path(loadid_yaml_node_t *const *stack, int depth, int next_item, char *buf,
                         size_t len) {
    const loadid_yaml_node_t *at = NULL;
    if (depth > 0) {
        at = stack[depth - 1];
        if (at->kind == LOADID_YAML_MAPPING && at->count % 2 == 1) at = at->child[at->count - 1];
    }
    size_t pos = loadid_yaml_path(at, buf, len);
    if (next_item && at && at->kind == LOADID_YAML_SEQUENCE) {
        if (!at->parent) pos = 0; /* "[2]", not "(top level)[2]" */
        char idx[32];
        const int k = snprintf(idx, sizeof idx, "[%zu]", at->count);
        put(buf, len, &pos, idx, (size_t)k);
        if (len > 0) buf[pos < len ? pos : len - 1] = '\0';
    }
}

static int syntax_error(loadid_yaml_doc_t *doc, const yaml_parser_t *parser, const char *text,
                        size_t len, loadid_yaml_node_t *const *stack, int depth) {
    if (parser->error == YAML_MEMORY_ERROR) return out_of_memory(doc);
    char path[512];
    current_path(stack, depth, 0, path, sizeof path);
    const char *problem = parser->problem ? parser->problem : "malformed YAML";
    if (parser->error == YAML_READER_ERROR) {
        /* Encoding errors carry a byte offset, not a mark; and libyaml
         * decodes its input in 16 kB chunks ahead of the parser, so the
         * node being built says nothing about where the bad byte is. */
        snprintf(path, sizeof path, "%s", kTopLevel);
        size_t line = 0;
        const size_t end = parser->problem_offset < len ? parser->problem_offset : len;
        for (size_t i = 0; i < end; ++i) line += text[i] == '\n';
        return fail_line(doc, clamp_line(line), path, "syntax error: %s (byte %zu)", problem,
                         parser->problem_offset);
    }
    const int line = clamp_line(parser->problem_mark.line);
    if (parser->context)
        return fail_line(doc, line, path, "syntax error: %s (%s on line %d)", problem,
                         parser->context, clamp_line(parser->context_mark.line));
    return fail_line(doc, line, path, "syntax error: %s", problem);
}

static int build(loadid_yaml_doc_t *doc, const char *text, size_t len) {
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) return out_of_memory(doc);
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, len);
    loadid_yaml_node_t *stack[LOADID_YAML_MAX_DEPTH];
    int depth = 0, documents = 0, done = 0, rc = 0;
    while (!done && rc == 0) {
        yaml_event_t ev;
        if (!yaml_parser_parse(&parser, &ev)) {
            rc = syntax_error(doc, &parser, text, len, stack, depth);
            break;
        }
        const int line = clamp_line(ev.start_mark.line);
        loadid_yaml_node_t *node = NULL;
        switch (ev.type) {
            case YAML_STREAM_END_EVENT:
                done = 1;
                break;
            case YAML_DOCUMENT_START_EVENT:
                if (++documents > 1)
                    rc = fail_line(doc, line, kTopLevel,
                                   "a second YAML document: one document per file");
                break;
            case YAML_ALIAS_EVENT: {
                char path[512];
                current_path(stack, depth, 1, path, sizeof path);
                rc = fail_line(doc, line, path, "alias *%s: aliases are not supported",
                               (const char *)ev.data.alias.anchor);
                break;
            }
            case YAML_SCALAR_EVENT: {
                node = new_node(doc, LOADID_YAML_SCALAR, &ev.start_mark);
                if (!node || !(node->text = malloc(ev.data.scalar.length + 1))) {
                    rc = out_of_memory(doc);
                    break;
                }
                memcpy(node->text, ev.data.scalar.value, ev.data.scalar.length);
                node->text[ev.data.scalar.length] = '\0';
                node->length = ev.data.scalar.length;
                const char *tag = (const char *)ev.data.scalar.tag;
                node->plain = ev.data.scalar.style == YAML_PLAIN_SCALAR_STYLE &&
                              !(tag && !strcmp(tag, YAML_STR_TAG));
                rc = attach(doc, stack, depth, node);
                break;
            }
            case YAML_SEQUENCE_START_EVENT:
            case YAML_MAPPING_START_EVENT: {
                const loadid_yaml_kind_t kind = ev.type == YAML_MAPPING_START_EVENT
                                                    ? LOADID_YAML_MAPPING
                                                    : LOADID_YAML_SEQUENCE;
                node = new_node(doc, kind, &ev.start_mark);
                if (!node) {
                    rc = out_of_memory(doc);
                    break;
                }
                rc = attach(doc, stack, depth, node);
                if (rc == 0 && depth == LOADID_YAML_MAX_DEPTH)
                    rc = loadid_yaml_fail(node, "nested deeper than %d levels",
                                          LOADID_YAML_MAX_DEPTH);
                if (rc == 0) stack[depth++] = node;
                break;
            }
            case YAML_SEQUENCE_END_EVENT:
            case YAML_MAPPING_END_EVENT:
                if (depth > 0) --depth;
                break;
            default:
                break; /* stream start, document end */
        }
        yaml_event_delete(&ev);
    }
    yaml_parser_delete(&parser);
    if (rc == 0 && doc->root && is_null_scalar(doc->root)) doc->root = NULL;
    return rc;
}

int loadid_yaml_load_string(const char *name, const char *text, size_t len, loadid_yaml_doc_t **out,
                            char *err, size_t errlen) {
    if (out) *out = NULL;
    if (!name || (!text && len) || !out) {
        if (err && errlen) snprintf(err, errlen, "loadid_yaml_load_string: invalid argument");
        return -EINVAL;
    }
    loadid_yaml_doc_t *doc = calloc(1, sizeof *doc);
    if (!doc || !(doc->file = strdup(name))) {
        free(doc);
        if (err && errlen) snprintf(err, errlen, "%s: out of memory", name);
        return -ENOMEM;
    }
    const int rc = build(doc, text ? text : "", len);
    if (rc < 0) {
        if (err && errlen) snprintf(err, errlen, "%s", doc->error);
        loadid_yaml_free(doc);
        return rc;
    }
    *out = doc;
    return 0;
}

int loadid_yaml_load_file(const char *path, loadid_yaml_doc_t **out, char *err, size_t errlen) {
    if (out) *out = NULL;
    if (!path || !out) {
        if (err && errlen) snprintf(err, errlen, "loadid_yaml_load_file: invalid argument");
        return -EINVAL;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        const int e = errno ? errno : EIO;
        if (err && errlen) snprintf(err, errlen, "%s: cannot read: %s", path, strerror(e));
        return -e;
    }
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int e = 0;
    for (;;) {
        char *more = grow(buf, &cap, len + 65536, 1);
        if (!more) {
            e = ENOMEM;
            break;
        }
        buf = more;
        errno = 0;
        const size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (len > LOADID_YAML_MAX_BYTES) {
            e = EFBIG;
            break;
        }
        if (got == 0) {
            if (ferror(f)) e = errno ? errno : EIO;
            break;
        }
    }
    fclose(f);
    int rc;
    if (e) {
        if (err && errlen) {
            if (e == EFBIG)
                snprintf(err, errlen, "%s: cannot read: larger than %u MiB", path,
                         LOADID_YAML_MAX_BYTES >> 20);
            else
                snprintf(err, errlen, "%s: cannot read: %s", path, strerror(e));
        }
        rc = -e;
    } else {
        rc = loadid_yaml_load_string(path, buf, len, out, err, errlen);
    }
    free(buf);
    return rc;
}

void loadid_yaml_free(loadid_yaml_doc_t *doc) {
    if (!doc) return;
    for (size_t i = 0; i < doc->n_all; ++i) {
        free(doc->all[i]->text);
        free(doc->all[i]->child);
        for (size_t k = 0; k < doc->all[i]->n_asked; ++k) free(doc->all[i]->asked[k]);
        free(doc->all[i]->asked);
        free(doc->all[i]);
    }
    free(doc->all);
    free(doc->file);
    free(doc);
}

loadid_yaml_node_t *loadid_yaml_root(const loadid_yaml_doc_t *doc) {
    return doc ? doc->root : NULL;
}
const char *loadid_yaml_file(const loadid_yaml_doc_t *doc) {
    return doc ? doc->file : NULL;
}
const char *loadid_yaml_error(const loadid_yaml_doc_t *doc) {
    return doc ? doc->error : "";
}

/* --- Nodes ---------------------------------------------------------------- */

loadid_yaml_kind_t loadid_yaml_kind(const loadid_yaml_node_t *node) {
    return node->kind;
}
int loadid_yaml_line(const loadid_yaml_node_t *node) {
    return node->line;
}

size_t loadid_yaml_count(const loadid_yaml_node_t *node) {
    if (!node) return 0;
    if (node->kind == LOADID_YAML_SEQUENCE) return node->count;
    if (node->kind == LOADID_YAML_MAPPING) return node->count / 2;
    return 0;
}

loadid_yaml_node_t *loadid_yaml_item(const loadid_yaml_node_t *node, size_t i) {
    if (!node || node->kind != LOADID_YAML_SEQUENCE || i >= node->count) return NULL;
    return node->child[i];
}

loadid_yaml_node_t *loadid_yaml_key_at(const loadid_yaml_node_t *node, size_t i) {
    if (!node || node->kind != LOADID_YAML_MAPPING || i >= node->count / 2) return NULL;
    return node->child[2 * i];
}

loadid_yaml_node_t *loadid_yaml_value_at(const loadid_yaml_node_t *node, size_t i) {
    if (!node || node->kind != LOADID_YAML_MAPPING || i >= node->count / 2) return NULL;
    return node->child[2 * i + 1];
}

const char *loadid_yaml_scalar(const loadid_yaml_node_t *node, size_t *len) {
    if (!node || node->kind != LOADID_YAML_SCALAR) return NULL;
    if (len) *len = node->length;
    return node->text;
}

int loadid_yaml_is_null(const loadid_yaml_node_t *node) {
    return node && is_null_scalar(node);
}

/* Remembers key as one a reader knows in map. Out of memory, it is not
 * remembered: only a suggestion is lost. */
static void remember_asked(loadid_yaml_node_t *map, const char *key) {
    for (size_t i = 0; i < map->n_asked; ++i)
        if (!strcmp(map->asked[i], key)) return;
    char **room = grow(map->asked, &map->cap_asked, map->n_asked + 1, sizeof *map->asked);
    if (!room) return;
    map->asked = room;
    if ((room[map->n_asked] = strdup(key))) map->n_asked++;
}

loadid_yaml_node_t *loadid_yaml_get(loadid_yaml_node_t *map, const char *key) {
    if (!map || !key || map->kind != LOADID_YAML_MAPPING) return NULL;
    remember_asked(map, key);
    const size_t len = strlen(key);
    for (size_t i = 0; i + 1 < map->count; i += 2) {
        if (same_text(map->child[i], key, len)) {
            map->child[i + 1]->used = 1;
            return map->child[i + 1];
        }
    }
    return NULL;
}

void loadid_yaml_mark_used(loadid_yaml_node_t *value) {
    if (value) value->used = 1;
}

/* Optimal string alignment distance (Levenshtein plus the swap of two
 * neighbours, the commonest typo: "mehtods"), each edit 1; stops counting
 * at cap + 1. Bytes, not characters: keys are ASCII in practice. */
static size_t edit_distance(const char *a, size_t la, const char *b, size_t lb, size_t cap) {
    enum { MAX = 64 };
    if (la > MAX || lb > MAX) return cap + 1;
    if ((la > lb ? la - lb : lb - la) > cap) return cap + 1;
    size_t d[MAX + 1][MAX + 1];
    for (size_t i = 0; i <= la; ++i) d[i][0] = i;
    for (size_t j = 0; j <= lb; ++j) d[0][j] = j;
    for (size_t i = 1; i <= la; ++i) {
        for (size_t j = 1; j <= lb; ++j) {
            size_t best = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
            if (d[i - 1][j] + 1 < best) best = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < best) best = d[i][j - 1] + 1;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < best)
                best = d[i - 2][j - 2] + 1;
            d[i][j] = best;
        }
    }
    return d[la][lb];
}

/* How far a name may be from a known one and still be taken for it: one
 * edit in names of up to 4 characters, two up to 8, three beyond; and
 * never as many edits as the typed name has characters ("x" is no typo of
 * "cpu"). */
static size_t edit_limit(size_t known_len) {
    return known_len <= 4 ? 1 : known_len <= 8 ? 2 : 3;
}

const char *loadid_yaml_suggest(const loadid_yaml_node_t *map, const char *text) {
    if (!map || !text || map->kind != LOADID_YAML_MAPPING) return NULL;
    const size_t lt = strlen(text);
    const char *best = NULL;
    size_t best_d = SIZE_MAX;
    for (size_t i = 0; i < map->n_asked; ++i) {
        const char *k = map->asked[i];
        const size_t lk = strlen(k), limit = edit_limit(lk);
        const size_t d = edit_distance(text, lt, k, lk, limit);
        if (d <= limit && d < lt && d < best_d) best = k, best_d = d;
    }
    return best;
}

size_t loadid_yaml_known_keys(const loadid_yaml_node_t *map, char *buf, size_t len) {
    size_t pos = 0;
    if (map && map->kind == LOADID_YAML_MAPPING)
        for (size_t i = 0; i < map->n_asked; ++i) {
            if (i > 0) put(buf, len, &pos, ", ", 2);
            put(buf, len, &pos, map->asked[i], strlen(map->asked[i]));
        }
    if (len > 0) buf[pos < len ? pos : len - 1] = '\0';
    return pos;
}

static int walk_unused(const loadid_yaml_node_t *n,
                       void (*fn)(void *, const loadid_yaml_unused_t *), void *ctx) {
    int found = 0;
    if (n->kind == LOADID_YAML_MAPPING) {
        for (size_t i = 0; i + 1 < n->count; i += 2) {
            const loadid_yaml_node_t *k = n->child[i], *v = n->child[i + 1];
            if (v->used) {
                found += walk_unused(v, fn, ctx);
                continue;
            }
            ++found;
            if (fn) {
                const loadid_yaml_unused_t u = {k, n, loadid_yaml_suggest(n, k->text)};
                fn(ctx, &u);
            }
        }
    } else if (n->kind == LOADID_YAML_SEQUENCE) {
        for (size_t i = 0; i < n->count; ++i) found += walk_unused(n->child[i], fn, ctx);
    }
    return found;
}

int loadid_yaml_each_unused(const loadid_yaml_doc_t *doc,
                            void (*fn)(void *ctx, const loadid_yaml_unused_t *u), void *ctx) {
    return doc && doc->root ? walk_unused(doc->root, fn, ctx) : 0;
}

typedef struct {
    void (*fn)(void *ctx, const char *msg);
    void *ctx;
} report_sink_t;

static void report_one(void *ctx, const loadid_yaml_unused_t *u) {
    const report_sink_t *r = ctx;
    char path[512], msg[1024];
    loadid_yaml_path(u->key, path, sizeof path);
    if (u->suggestion)
        snprintf(msg, sizeof msg, "%s:%d: %s: unknown key, ignored (did you mean '%s'?)",
                 u->key->doc->file, u->key->line, path, u->suggestion);
    else
        snprintf(msg, sizeof msg, "%s:%d: %s: unknown key, ignored", u->key->doc->file,
                 u->key->line, path);
    one_line(msg);
    r->fn(r->ctx, msg);
}

int loadid_yaml_report_unused(const loadid_yaml_doc_t *doc, void (*fn)(void *ctx, const char *msg),
                              void *ctx) {
    report_sink_t r = {fn, ctx};
    return loadid_yaml_each_unused(doc, fn ? report_one : NULL, &r);
}

/* --- Typed conversions ---------------------------------------------------- */

static int is_digit(char c) {
    return c >= '0' && c <= '9';
}

static int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)? over the whole text. */
static int is_decimal_number(const char *s) {
    if (*s == '+' || *s == '-') ++s;
    size_t whole = 0, frac = 0;
    while (is_digit(*s)) ++s, ++whole;
    if (*s == '.') {
        ++s;
        while (is_digit(*s)) ++s, ++frac;
    }
    if (whole == 0 && frac == 0) return 0;
    if (*s == 'e' || *s == 'E') {
        ++s;
        if (*s == '+' || *s == '-') ++s;
        if (!is_digit(*s)) return 0;
        while (is_digit(*s)) ++s;
    }
    return *s == '\0';
}

/* .nan, .inf, -.Inf, nan, Infinity...: what strtod would take as non-finite. */
static int is_nonfinite_spelling(const char *s) {
    if (*s == '+' || *s == '-') ++s;
    if (*s == '.') ++s;
    static const char *const kWords[] = {"nan", "inf", "infinity"};
    for (size_t w = 0; w < 3; ++w) {
        const char *a = s, *b = kWords[w];
        while (*a && *b && (*a | 0x20) == *b) ++a, ++b;
        if (!*a && !*b) return 1;
    }
    return 0;
}

/* The scalar must be plain, non-null and hold no NUL; else an error saying
 * "expected <what>, got ...". */
static int need_plain(const loadid_yaml_node_t *n, const char *what) {
    char buf[96];
    if (n->kind != LOADID_YAML_SCALAR || !n->plain || is_null_scalar(n) ||
        strlen(n->text) != n->length)
        return loadid_yaml_fail(n, "expected %s, got %s", what, describe(n, buf, sizeof buf));
    return 0;
}

int loadid_yaml_as_double(const loadid_yaml_node_t *node, double *out) {
    if (need_plain(node, "a number")) return -EINVAL;
    char buf[96];
    if (is_nonfinite_spelling(node->text))
        return loadid_yaml_fail(node, "expected a finite number, got %s",
                                describe(node, buf, sizeof buf));
    if (!is_decimal_number(node->text))
        return loadid_yaml_fail(node, "expected a number, got %s", describe(node, buf, sizeof buf));
    errno = 0;
    const double v = strtod(node->text, NULL);
    if (!isfinite(v)) /* overflow: ERANGE and HUGE_VAL; underflow to 0 is fine */
        return loadid_yaml_fail(node, "number out of range: %s", describe(node, buf, sizeof buf));
    *out = v;
    return 0;
}

/* Decimal or 0x hexadecimal, optionally signed: the magnitude and sign. */
static int parse_integer(const loadid_yaml_node_t *node, int *negative, uint64_t *magnitude) {
    if (need_plain(node, "an integer")) return -EINVAL;
    const char *s = node->text;
    char buf[96];
    *negative = 0;
    if (*s == '+' || *s == '-') *negative = *s++ == '-';
    uint64_t m = 0;
    int base = 10, digits = 0, overflow = 0;
    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) base = 16, s += 2;
    for (; *s; ++s, ++digits) {
        const int d = base == 16 ? hex_value(*s) : (is_digit(*s) ? *s - '0' : -1);
        if (d < 0) break;
        if (m > (UINT64_MAX - (uint64_t)d) / (uint64_t)base)
            overflow = 1;
        else
            m = m * (uint64_t)base + (uint64_t)d;
    }
    if (*s || digits == 0)
        return loadid_yaml_fail(node, "expected an integer, got %s",
                                describe(node, buf, sizeof buf));
    if (overflow)
        return loadid_yaml_fail(node, "integer out of range: %s", describe(node, buf, sizeof buf));
    *magnitude = m;
    return 0;
}

int loadid_yaml_as_int(const loadid_yaml_node_t *node, int *out) {
    int neg;
    uint64_t m;
    if (parse_integer(node, &neg, &m)) return -EINVAL;
    if (m > (neg ? (uint64_t)INT_MAX + 1 : (uint64_t)INT_MAX)) {
        char buf[96];
        return loadid_yaml_fail(node, "integer out of range (%d..%d): %s", INT_MIN, INT_MAX,
                                describe(node, buf, sizeof buf));
    }
    *out = neg ? (int)(-(int64_t)m) : (int)m;
    return 0;
}

int loadid_yaml_as_uint64(const loadid_yaml_node_t *node, uint64_t *out) {
    int neg;
    uint64_t m;
    if (parse_integer(node, &neg, &m)) return -EINVAL;
    if (neg && m != 0) {
        char buf[96];
        return loadid_yaml_fail(node, "expected a non-negative integer, got %s",
                                describe(node, buf, sizeof buf));
    }
    *out = m;
    return 0;
}

int loadid_yaml_as_bool(const loadid_yaml_node_t *node, int *out) {
    if (need_plain(node, "true or false")) return -EINVAL;
    static const char *const kTrue[] = {"true", "True", "TRUE"};
    static const char *const kFalse[] = {"false", "False", "FALSE"};
    for (size_t i = 0; i < 3; ++i) {
        if (!strcmp(node->text, kTrue[i])) {
            *out = 1;
            return 0;
        }
        if (!strcmp(node->text, kFalse[i])) {
            *out = 0;
            return 0;
        }
    }
    char buf[96];
    return loadid_yaml_fail(node, "expected true or false, got %s",
                            describe(node, buf, sizeof buf));
}

int loadid_yaml_as_string(const loadid_yaml_node_t *node, char *buf, size_t size) {
    char d[96];
    if (node->kind != LOADID_YAML_SCALAR || is_null_scalar(node))
        return loadid_yaml_fail(node, "expected a string, got %s", describe(node, d, sizeof d));
    if (strlen(node->text) != node->length)
        return loadid_yaml_fail(node, "a string with a NUL character");
    if (size == 0 || node->length > size - 1)
        return loadid_yaml_fail(node, "longer than %zu characters", size ? size - 1 : 0);
    memcpy(buf, node->text, node->length + 1);
    return 0;
}

int loadid_yaml_as_doubles(const loadid_yaml_node_t *node, double *out, size_t min, size_t max,
                           size_t *count) {
    char d[96];
    if (node->kind != LOADID_YAML_SEQUENCE) {
        if (min == max)
            return loadid_yaml_fail(node, "expected a sequence of %zu numbers, got %s", min,
                                    describe(node, d, sizeof d));
        return loadid_yaml_fail(node, "expected a sequence of numbers, got %s",
                                describe(node, d, sizeof d));
    }
    const size_t n = node->count;
    if (min == max && n != min)
        return loadid_yaml_fail(node, "expected %zu numbers, got %zu", min, n);
    if (n < min)
        return loadid_yaml_fail(node, "expected at least %zu number%s, got %zu", min,
                                min == 1 ? "" : "s", n);
    if (n > max)
        return loadid_yaml_fail(node, "expected at most %zu number%s, got %zu", max,
                                max == 1 ? "" : "s", n);
    for (size_t i = 0; i < n; ++i)
        if (loadid_yaml_as_double(node->child[i], &out[i])) return -EINVAL;
    if (count) *count = n;
    return 0;
}

/* --- Getters -------------------------------------------------------------- */

/* The value of key, or NULL with *rc 0 (absent) or -EINVAL (map is not a
 * mapping). */
static loadid_yaml_node_t *lookup(loadid_yaml_node_t *map, const char *key, int *rc) {
    *rc = 0;
    if (!map) return NULL;
    if (map->kind != LOADID_YAML_MAPPING) {
        char d[96];
        *rc = loadid_yaml_fail(map, "expected a mapping, got %s", describe(map, d, sizeof d));
        return NULL;
    }
    return loadid_yaml_get(map, key);
}

#define LOADID_YAML_GETTER(name, type, conversion)                  \
    int name(loadid_yaml_node_t *map, const char *key, type *out) { \
        int rc;                                                     \
        loadid_yaml_node_t *n = lookup(map, key, &rc);              \
        if (!n) return rc;                                          \
        return conversion(n, out) ? -EINVAL : 1;                    \
    }

LOADID_YAML_GETTER(loadid_yaml_get_double, double, loadid_yaml_as_double)
LOADID_YAML_GETTER(loadid_yaml_get_int, int, loadid_yaml_as_int)
LOADID_YAML_GETTER(loadid_yaml_get_uint64, uint64_t, loadid_yaml_as_uint64)
LOADID_YAML_GETTER(loadid_yaml_get_bool, int, loadid_yaml_as_bool)

int loadid_yaml_get_mapping(loadid_yaml_node_t *map, const char *key, loadid_yaml_node_t **out) {
    int rc;
    loadid_yaml_node_t *n = lookup(map, key, &rc);
    *out = NULL;
    if (!n || is_null_scalar(n)) return rc;
    if (n->kind != LOADID_YAML_MAPPING) {
        char d[96];
        return loadid_yaml_fail(n, "expected a mapping, got %s", describe(n, d, sizeof d));
    }
    *out = n;
    return 1;
}

int loadid_yaml_get_sequence(loadid_yaml_node_t *map, const char *key, loadid_yaml_node_t **out) {
    int rc;
    loadid_yaml_node_t *n = lookup(map, key, &rc);
    if (!n) return rc;
    if (n->kind != LOADID_YAML_SEQUENCE) {
        char d[96];
        return loadid_yaml_fail(n, "expected a sequence, got %s", describe(n, d, sizeof d));
    }
    *out = n;
    return 1;
}

int loadid_yaml_get_string(loadid_yaml_node_t *map, const char *key, char *buf, size_t size) {
    int rc;
    loadid_yaml_node_t *n = lookup(map, key, &rc);
    if (!n) return rc;
    return loadid_yaml_as_string(n, buf, size) ? -EINVAL : 1;
}

int loadid_yaml_get_doubles(loadid_yaml_node_t *map, const char *key, double *out, size_t n) {
    return loadid_yaml_get_double_seq(map, key, out, n, n, NULL);
}

int loadid_yaml_get_double_seq(loadid_yaml_node_t *map, const char *key, double *out, size_t min,
                               size_t max, size_t *count) {
    int rc;
    loadid_yaml_node_t *n = lookup(map, key, &rc);
    if (!n) return rc;
    return loadid_yaml_as_doubles(n, out, min, max, count) ? -EINVAL : 1;
}
