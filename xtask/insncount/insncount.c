/*
 * beamfield's instruction counter: a QEMU TCG plugin that counts the guest instructions
 * executed between two marker addresses (the firmware's `bench_mark_start` and
 * `bench_mark_end`, see firmware/src/lib.rs).
 *
 * Every translated instruction gets an inline 64-bit add on one counter, so the count is
 * exact whatever interrupts or exceptions do to a translation block. The two marker
 * instructions also get a callback, which QEMU runs before that instruction's own add: a
 * region therefore counts from the start marker's first instruction (excluded) up to the end
 * marker's first instruction (excluded), and a call of both markers back to back reads as the
 * fixed cost of the calls themselves.
 *
 * Arguments:  -plugin libinsncount.so,start=0xADDR,end=0xADDR   (-d plugin prints the lines)
 * Output:     "insncount: region K: N instructions" per end marker reached (K from 0), then
 *             "insncount: total N" when QEMU exits.
 *
 * QEMU's plugin API changed under this file's feet: QEMU 7.2 and 8.x accept API version 1 and
 * offer `qemu_plugin_register_vcpu_insn_exec_inline` (an add on a plain counter); QEMU 9.0 added
 * per-vCPU scoreboards (`..._inline_per_vcpu`) and QEMU 10 removed the old call and refuses
 * version 1 (it accepts 2 to 4). Debian ships QEMU's plugin API without its header, so the entry
 * points used are declared here, the version-dependent ones weak: whichever the running QEMU
 * exports is found when it loads the plugin, and a constructor, which runs inside QEMU's
 * dlopen() before QEMU reads `qemu_plugin_version`, declares the API version that goes with it.
 * Both paths add 1 per executed instruction with an inline add and run the same marker
 * callbacks, so the counts do not depend on the QEMU version. `cargo xtask` builds this file
 * with gcc when a count is asked for.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t plugin_id;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
struct qemu_info_t;
struct qemu_plugin_scoreboard;

/* QEMU >= 9.0: a 64-bit entry of a scoreboard, passed by value. */
typedef struct {
    struct qemu_plugin_scoreboard *score;
    size_t offset;
} plugin_u64;

enum cb_flags { CB_NO_REGS = 0 };
enum inline_op { INLINE_ADD_U64 = 0 };

/* In every QEMU from 7.2 to 10.x. */
extern void qemu_plugin_register_vcpu_tb_trans_cb(
    plugin_id, void (*)(plugin_id, struct qemu_plugin_tb *));
extern size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
extern struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
extern uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
extern void qemu_plugin_register_vcpu_insn_exec_cb(
    struct qemu_plugin_insn *, void (*)(unsigned int, void *), enum cb_flags, void *);
extern void qemu_plugin_register_atexit_cb(plugin_id, void (*)(plugin_id, void *), void *);
extern void qemu_plugin_outs(const char *);

/* API version 1 only (QEMU 7.2, 8.x); gone in QEMU 10. */
extern void qemu_plugin_register_vcpu_insn_exec_inline(
    struct qemu_plugin_insn *, enum inline_op, void *, uint64_t) __attribute__((weak));
/* QEMU 9.0 and later. */
extern struct qemu_plugin_scoreboard *qemu_plugin_scoreboard_new(size_t) __attribute__((weak));
extern void qemu_plugin_register_vcpu_insn_exec_inline_per_vcpu(
    struct qemu_plugin_insn *, enum inline_op, plugin_u64, uint64_t) __attribute__((weak));
extern uint64_t qemu_plugin_u64_sum(plugin_u64) __attribute__((weak));

/* Set by `choose_api` when QEMU loads the plugin: 1 (old inline call) or 2 (scoreboards; QEMU 10
   accepts 2 to 4 and 2 is all this file needs). It stays 0 when the running QEMU offers
   neither inline call, and QEMU then refuses to load the plugin (API version 0 is below every
   QEMU's minimum) instead of counting wrongly. */
__attribute__((visibility("default"))) int qemu_plugin_version = 0;

static int per_vcpu_api(void) {
    return qemu_plugin_register_vcpu_insn_exec_inline_per_vcpu && qemu_plugin_scoreboard_new &&
           qemu_plugin_u64_sum;
}

__attribute__((constructor)) static void choose_api(void) {
    if (per_vcpu_api()) {
        qemu_plugin_version = 2;
    } else if (qemu_plugin_register_vcpu_insn_exec_inline) {
        qemu_plugin_version = 1;
    }
}

/* The guest's single core. API 1: one plain counter. API 2: one scoreboard entry per vCPU,
   summed when read (the guest has one vCPU, so the sum is that vCPU's count). */
static uint64_t executed_v1;
static plugin_u64 executed_v2;

static uint64_t executed(void) {
    return qemu_plugin_version == 2 ? qemu_plugin_u64_sum(executed_v2) : executed_v1;
}

static uint64_t region_start;
static unsigned regions_done;
static int in_region;
/* Thumb addresses: the symbol's low bit is cleared. UINT64_MAX means "not given". */
static uint64_t start_pc = UINT64_MAX;
static uint64_t end_pc = UINT64_MAX;

static void say(const char *text) { qemu_plugin_outs(text); }

static void start_marker(unsigned int vcpu, void *unused) {
    (void)vcpu; (void)unused;
    region_start = executed();
    in_region = 1;
}

static void end_marker(unsigned int vcpu, void *unused) {
    char line[80];
    (void)vcpu; (void)unused;
    if (!in_region) {
        say("insncount: end marker reached outside a region (ignored)\n");
        return;
    }
    in_region = 0;
    snprintf(line, sizeof line, "insncount: region %u: %llu instructions\n", regions_done,
             (unsigned long long)(executed() - region_start));
    regions_done++;
    say(line);
}

static void on_translate(plugin_id id, struct qemu_plugin_tb *tb) {
    size_t count = qemu_plugin_tb_n_insns(tb);
    (void)id;
    for (size_t k = 0; k < count; k++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, k);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        if (pc == start_pc) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, start_marker, CB_NO_REGS, NULL);
        } else if (pc == end_pc) {
            qemu_plugin_register_vcpu_insn_exec_cb(insn, end_marker, CB_NO_REGS, NULL);
        }
        if (qemu_plugin_version == 2) {
            qemu_plugin_register_vcpu_insn_exec_inline_per_vcpu(insn, INLINE_ADD_U64, executed_v2, 1);
        } else {
            qemu_plugin_register_vcpu_insn_exec_inline(insn, INLINE_ADD_U64, &executed_v1, 1);
        }
    }
}

static void on_qemu_exit(plugin_id id, void *unused) {
    char line[64];
    (void)id; (void)unused;
    snprintf(line, sizeof line, "insncount: total %llu\n", (unsigned long long)executed());
    say(line);
}

static int parse_address(const char *arg, const char *key, uint64_t *out) {
    size_t n = strlen(key);
    char *end;
    if (strncmp(arg, key, n) != 0) {
        return 0;
    }
    *out = strtoull(arg + n, &end, 0) & ~(uint64_t)1;
    return *end == '\0' ? 1 : -1;
}

__attribute__((visibility("default"))) int qemu_plugin_install(
    plugin_id id, const struct qemu_info_t *info, int argc, char **argv) {
    (void)info;
    for (int k = 0; k < argc; k++) {
        int got = parse_address(argv[k], "start=", &start_pc);
        if (got == 0) {
            got = parse_address(argv[k], "end=", &end_pc);
        }
        if (got != 1) {
            fprintf(stderr, "insncount: bad argument '%s' (expected start=ADDR or end=ADDR)\n",
                    argv[k]);
            return -1;
        }
    }
    if (start_pc == UINT64_MAX || end_pc == UINT64_MAX || start_pc == end_pc) {
        fprintf(stderr, "insncount: needs two different addresses, start= and end=\n");
        return -1;
    }
    if (qemu_plugin_version == 2) {
        executed_v2.score = qemu_plugin_scoreboard_new(sizeof(uint64_t));
        executed_v2.offset = 0;
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, on_qemu_exit, NULL);
    return 0;
}
