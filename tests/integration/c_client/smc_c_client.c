/* A DDS program of someone else's, written against the Cyclone DDS C API and
 * the project's IDL alone (idl/smc_data.idl through idlc; none of the
 * project's own libraries), following idl/README.md: it joins a running
 * cell, reads a mill's force summaries and supervisor situation, and holds
 * the mill's feed with an operator command, then releases it.
 *
 *   smc-c-client --machine mill-1 [--partition P] [--operator NAME] [--timeout S]
 *   smc-c-client --machine mill-1 --posing-from mill-2 [--partition P] [--timeout S]
 *
 * Exit status: 0 when the mill obeyed (module C, the feed hold, active in
 * its situation after the command, and released after the second), 1 when
 * it did not within the timeout, 2 for a usage or DDS error. The DDS
 * profile comes from CYCLONEDDS_URI as for every participant of the cell.
 *
 * --posing-from M: what an edge of mill M would have to do to speak for
 * another mill: from M's partition, write a chatter event about --machine
 * (the cell must refuse it). Exit status 0 when the event was written to a
 * matched reader, 1 when no reader matched within the timeout, 2 for an
 * error (e.g. a writer refused by access control). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "smc_data.h"

#define MODULE_C (1u << 2)

static int64_t now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static int64_t mono_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static int fail_dds(const char* what, dds_return_t rc) {
  fprintf(stderr, "smc-c-client: %s: %s\n", what, dds_strretcode(rc));
  return 2;
}

/* The latest situation of `machine` (0 when none arrived). */
static int read_situation(dds_entity_t reader, const char* machine, uint32_t* modules) {
  void* samples[16] = {0};
  dds_sample_info_t infos[16];
  int found = 0;
  dds_return_t n = dds_take(reader, samples, infos, 16, 16);
  for (dds_return_t i = 0; i < n; i++) {
    const smc_data_SupervisorSituation* s = samples[i];
    if (infos[i].valid_data && strcmp(s->machine_id, machine) == 0) {
      *modules = s->modules_active;
      found = 1;
    }
  }
  if (n > 0) dds_return_loan(reader, samples, n);
  return found;
}

static dds_return_t send_command(dds_entity_t writer, const char* machine, const char* op,
                                 int32_t action, uint64_t id) {
  smc_data_OperatorCommand c;
  memset(&c, 0, sizeof c);
  snprintf(c.machine_id, sizeof c.machine_id, "%s", machine);
  snprintf(c.operator_name, sizeof c.operator_name, "%s", op);
  c.command_id = id;
  c.issued_unix_ns = (uint64_t)now_ns();
  c.action = action;
  return dds_write(writer, &c);
}

/* Waits until the situation's module C is `want` (1: held, 0: released). */
static int wait_hold(dds_entity_t reader, const char* machine, int want, int64_t deadline) {
  uint32_t modules = 0;
  while (mono_ns() < deadline) {
    if (read_situation(reader, machine, &modules) && ((modules & MODULE_C) != 0) == want) return 1;
    dds_sleepfor(DDS_MSECS(10));
  }
  return 0;
}

/* From another mill's partition, a chatter event about `machine`. */
static int pose(dds_entity_t participant, dds_entity_t pub, const char* machine, int64_t deadline) {
  /* smc_chatter_event: durable record, reliable, transient-local, keep last 1. */
  dds_entity_t t =
      dds_create_topic(participant, &smc_data_ChatterEvent_desc, "smc_chatter_event", NULL, NULL);
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  dds_entity_t w = t < 0 ? t : dds_create_writer(pub, t, q, NULL);
  dds_delete_qos(q);
  if (w < 0) {
    dds_delete(participant);
    return fail_dds("chatter event writer", w);
  }
  dds_publication_matched_status_t m = {0};
  while (mono_ns() < deadline) {
    if (dds_get_publication_matched_status(w, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  smc_data_ChatterEvent e;
  memset(&e, 0, sizeof e);
  snprintf(e.machine_id, sizeof e.machine_id, "%s", machine);
  e.event_id = (uint64_t)now_ns();
  e.source = smc_data_CHATTER_OPERATOR;
  snprintf(e.job_id, sizeof e.job_id, "%s", "posing");
  const dds_return_t rc = m.current_count > 0 ? dds_write(w, &e) : DDS_RETCODE_OK;
  printf("chatter event about %s: %s\n", machine,
         m.current_count == 0 ? "no reader matched"
         : rc == 0            ? "written"
                              : dds_strretcode(rc));
  /* Reliable: give the readers the sample before the participant goes. */
  if (rc == 0 && m.current_count > 0) dds_wait_for_acks(w, DDS_SECS(2));
  dds_delete(participant);
  if (rc != 0) return 2;
  return m.current_count > 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  const char *machine = NULL, *partition = "", *op = "c-client", *posing_from = NULL;
  double timeout_s = 30;
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "--machine") == 0 && i + 1 < argc) {
      machine = argv[++i];
    } else if (strcmp(argv[i], "--posing-from") == 0 && i + 1 < argc) {
      posing_from = argv[++i];
    } else if (strcmp(argv[i], "--partition") == 0 && i + 1 < argc) {
      partition = argv[++i];
    } else if (strcmp(argv[i], "--operator") == 0 && i + 1 < argc) {
      op = argv[++i];
    } else if (strcmp(argv[i], "--timeout") == 0 && i + 1 < argc) {
      timeout_s = atof(argv[++i]);
    } else {
      fprintf(stderr,
              "usage: %s --machine ID [--posing-from ID] [--partition P] [--operator NAME] "
              "[--timeout S]\n",
              argv[0]);
      return 2;
    }
  }
  if (machine == NULL || strlen(machine) > 31) {
    fprintf(stderr, "smc-c-client: --machine: a mill id of 1-31 characters is required\n");
    return 2;
  }
  const int64_t deadline = mono_ns() + (int64_t)(timeout_s * 1e9);

  dds_entity_t participant = dds_create_participant(DDS_DOMAIN_DEFAULT, NULL, NULL);
  if (participant < 0) return fail_dds("dds_create_participant", participant);
  /* The mill's partition, "<cell partition>/machine/<machine>" (idl/README.md:
   * an edge publishes and reads only there, so a client of one mill joins it). */
  char mill_partition[256];
  snprintf(mill_partition, sizeof mill_partition, "%s/machine/%s", partition,
           posing_from != NULL ? posing_from : machine);
  dds_qos_t* pq = dds_create_qos();
  dds_qset_partition1(pq, mill_partition);
  dds_entity_t sub = dds_create_subscriber(participant, pq, NULL);
  dds_entity_t pub = dds_create_publisher(participant, pq, NULL);
  dds_delete_qos(pq);
  if (sub < 0 || pub < 0) return fail_dds("publisher/subscriber", sub < 0 ? sub : pub);

  if (posing_from != NULL) return pose(participant, pub, machine, deadline);

  /* smc_force_summary: telemetry, best effort, keep last 8. */
  dds_entity_t t_sum =
      dds_create_topic(participant, &smc_data_ForceSummary_desc, "smc_force_summary", NULL, NULL);
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 8);
  dds_entity_t r_sum = dds_create_reader(sub, t_sum, q, NULL);
  dds_delete_qos(q);
  /* smc_supervisor_situation: state, reliable, transient-local, keep last 1. */
  dds_entity_t t_sit = dds_create_topic(participant, &smc_data_SupervisorSituation_desc,
                                        "smc_supervisor_situation", NULL, NULL);
  q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  dds_entity_t r_sit = dds_create_reader(sub, t_sit, q, NULL);
  dds_delete_qos(q);
  /* smc_operator_command: events, reliable, keep all, volatile. */
  dds_entity_t t_cmd = dds_create_topic(participant, &smc_data_OperatorCommand_desc,
                                        "smc_operator_command", NULL, NULL);
  q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  dds_entity_t w_cmd = dds_create_writer(pub, t_cmd, q, NULL);
  dds_delete_qos(q);
  if (t_sum < 0 || r_sum < 0 || t_sit < 0 || r_sit < 0 || t_cmd < 0 || w_cmd < 0) {
    dds_delete(participant);
    return fail_dds("topics, readers and writer", -1);
  }

  /* 1. Force summaries of the mill (it must be cutting). */
  int summaries = 0;
  float f_y = 0, f_ref = 0;
  while (summaries < 5 && mono_ns() < deadline) {
    void* samples[8] = {0};
    dds_sample_info_t infos[8];
    dds_return_t n = dds_take(r_sum, samples, infos, 8, 8);
    for (dds_return_t i = 0; i < n; i++) {
      const smc_data_ForceSummary* s = samples[i];
      if (infos[i].valid_data && strcmp(s->machine_id, machine) == 0) {
        summaries++;
        f_y = s->f_y_peak_n;
        f_ref = s->f_ref_n;
      }
    }
    if (n > 0) dds_return_loan(r_sum, samples, n);
    if (n <= 0) dds_sleepfor(DDS_MSECS(10));
  }
  printf("force summaries of %s: %d, last F_Y %.1f N (F_ref %.1f N)\n", machine, summaries,
         (double)f_y, (double)f_ref);
  /* 2. Its situation. */
  uint32_t modules = 0;
  int have = 0;
  while (!have && mono_ns() < deadline) {
    have = read_situation(r_sit, machine, &modules);
    if (!have) dds_sleepfor(DDS_MSECS(10));
  }
  printf("situation of %s: modules 0x%03" PRIx32 "\n", machine, modules);
  /* 3. Feed hold, as an operator tool would send it, once the edge's
   * command reader is matched. */
  dds_publication_matched_status_t m;
  while (mono_ns() < deadline) {
    if (dds_get_publication_matched_status(w_cmd, &m) == 0 && m.current_count > 0) break;
    dds_sleepfor(DDS_MSECS(10));
  }
  int ok = summaries >= 5 && have;
  uint64_t id = (uint64_t)now_ns();
  dds_return_t rc = send_command(w_cmd, machine, op, smc_data_OP_FEED_HOLD_ON, id);
  if (rc != 0) ok = 0;
  const int held = ok && wait_hold(r_sit, machine, 1, deadline);
  printf("feed hold on: %s\n", held ? "obeyed (module C active)" : "NOT obeyed");
  rc = send_command(w_cmd, machine, op, smc_data_OP_FEED_HOLD_OFF, id + 1);
  const int released = held && rc == 0 && wait_hold(r_sit, machine, 0, deadline);
  printf("feed hold off: %s\n", released ? "obeyed" : "NOT obeyed");
  dds_delete(participant);
  return ok && held && released ? 0 : 1;
}
