#include "engine/job_journal.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include "tests/support/meshes.h"

namespace meshflow::engine {
namespace {

using meshflow::testing::TempDir;

StepRecord step(int seq, const std::string& operation) {
  StepRecord s;
  s.seq = seq;
  s.operation = operation;
  s.state = "done";
  return s;
}

// A resumed job sets its current mesh's vertex count from the last replayed step's.
TEST(JobJournal, AStepKeepsItsOutputVertexCount) {
  TempDir dir;
  {
    JobJournal journal(dir.file("jobs.sqlite"));
    JobRecord job;
    job.id = "j";
    journal.create(job);
    StepRecord filled = step(0, "FillHoles");
    filled.output_vertices = 36'021;
    journal.put_step("j", filled);
    journal.put_step("j", step(1, "NumberOfComponents"));  // an analysis: no count
  }
  JobJournal reopened(dir.file("jobs.sqlite"));
  std::optional<JobRecord> job = reopened.get("j");
  ASSERT_TRUE(job);
  ASSERT_EQ(job->steps.size(), 2u);
  EXPECT_EQ(job->steps[0].output_vertices, 36'021u);
  EXPECT_EQ(job->steps[1].output_vertices, 0u);
}

// A journal written before steps had a vertex count opens, gains the column, and its steps
// read 0 (unknown).
TEST(JobJournal, AJournalWithoutTheVertexCountColumnStillOpens) {
  TempDir dir;
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(dir.file("jobs.sqlite").c_str(), &db), SQLITE_OK);
  const char* old_schema = R"sql(
CREATE TABLE jobs (id TEXT PRIMARY KEY, state TEXT NOT NULL, workflow_xml TEXT NOT NULL,
  workflow_id TEXT, input_path TEXT, input_sha256 TEXT, output_path TEXT, output_sha256 TEXT,
  error TEXT, created TEXT NOT NULL);
CREATE TABLE steps (job_id TEXT NOT NULL, seq INTEGER NOT NULL, operation TEXT, kind TEXT,
  node TEXT, state TEXT, run_ms INTEGER, transfer_ms INTEGER, update_ms INTEGER, sent TEXT,
  correction_bytes INTEGER, output_bytes INTEGER, value REAL, output_sha256 TEXT, output_url TEXT,
  correction_url TEXT, error TEXT, PRIMARY KEY (job_id, seq));
INSERT INTO jobs (id, state, workflow_xml, created) VALUES ('j', 'running', '<workflow/>', 'then');
INSERT INTO steps (job_id, seq, operation, state) VALUES ('j', 0, 'FillHoles', 'done');
)sql";
  ASSERT_EQ(sqlite3_exec(db, old_schema, nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
  JobJournal journal(dir.file("jobs.sqlite"));
  std::optional<JobRecord> job = journal.get("j");
  ASSERT_TRUE(job);
  ASSERT_EQ(job->steps.size(), 1u);
  EXPECT_EQ(job->steps[0].output_vertices, 0u);
  StepRecord simplified = step(1, "Simplify");
  simplified.output_vertices = 9'000;
  journal.put_step("j", simplified);
  EXPECT_EQ(journal.get("j")->steps[1].output_vertices, 9'000u);
}

}  // namespace
}  // namespace meshflow::engine
