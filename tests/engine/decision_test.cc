// The analysis's decisions as data (engine/include/insdiag/engine/decision.h):
// each kind renders the note the report carries, from its fields alone, and
// a log keeps notes and decisions in the order they were made.
#include "insdiag/engine/decision.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace insdiag::engine {
namespace {

bool Contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

Decision FaultTest(bool stands) {
  Decision d;
  d.kind = DecisionKind::kFaultAgainstDrifts;
  d.subjects = {"gyro_bias_step.x"};
  d.statistic = 58.74;
  d.degrees_of_freedom = 1;
  d.level = 0.01;
  d.p_value = stands ? 9.3e-12 : 1.0;
  d.adopted = stands;
  d.measures = {{"onset_s", 62.4}};
  return d;
}

TEST(DecisionTest, AFaultTestSaysWhereItStandsAndWhereItIsTheDriftsMisfit) {
  const std::string stands = RenderNote(FaultTest(true));
  EXPECT_TRUE(Contains(stands, "gyro_bias_step.x at 62 s")) << stands;
  EXPECT_TRUE(Contains(stands, "2Δℓ = 58.7 (p = 9.3e-12")) << stands;
  EXPECT_TRUE(Contains(stands, "it stands against the drifts")) << stands;
  const std::string misfit = RenderNote(FaultTest(false));
  EXPECT_TRUE(Contains(misfit, "— their misfit")) << misfit;
  EXPECT_EQ(FaultTest(true).Measure("onset_s"), 62.4);
  EXPECT_FALSE(FaultTest(true).Measure("iterations").has_value());
}

TEST(DecisionTest, DriftsIdentifiedRenderTheirTestAndWhatTheModelDid) {
  Decision d;
  d.kind = DecisionKind::kDriftsIdentified;
  d.subjects = {"gyro_bias_gm.x.sigma", "gyro_bias_gm.x.tau"};
  d.statistic = 140.4;
  d.degrees_of_freedom = 2;
  d.level = 0.01;
  d.measures = {{"iterations", 148}, {"filter_passes", 537}};
  d.adopted = true;
  EXPECT_EQ(RenderNote(d),
            "drift parameters identified by likelihood of the innovations: gyro_bias_gm.x.sigma, "
            "gyro_bias_gm.x.tau (EM, 148 iterations, 537 filter passes): 2Δℓ = 140.4 against χ²(2) at 0.01 — "
            "the model takes the estimates");
  d.qualifiers = {"not_converged", "placeholders"};
  EXPECT_TRUE(Contains(RenderNote(d), "148 iterations, not converged"));
  EXPECT_TRUE(Contains(RenderNote(d), "the Allan fit's placeholders: it takes the estimates"));
  d.adopted = false;
  EXPECT_TRUE(Contains(RenderNote(d), "the data do not reject the model's values, kept"));
}

TEST(DecisionTest, TheDriftsOverACandidateNameTheCandidateTheyRejected) {
  Decision d;
  d.kind = DecisionKind::kDriftsOverCandidate;
  d.statistic = -115.5;
  d.rejected = {{"gyro_scale_factor.z", -4.1}};
  d.adopted = true;
  EXPECT_TRUE(Contains(RenderNote(d), "(ΔBIC -115.5 against the best candidate's -4.1): the model takes them"));
  d.adopted = false;
  d.measures = {{"parameters", 2}};
  EXPECT_TRUE(Contains(RenderNote(d), "(2 parameters worth their cost) reach ΔBIC -115.5 against the best "
                                      "candidate's -4.1: the candidates stand"));
}

TEST(DecisionTest, TheReferenceNoiseListsEachRaisedGroupInItsUnit) {
  Decision d;
  d.kind = DecisionKind::kReferenceNoiseRaised;
  d.subjects = {"vertical position"};
  d.measures = {{"vertical position.before", 1e-6}, {"vertical position.after", 6.33e-5}};
  d.statistic = 167.7;
  d.degrees_of_freedom = 2;
  d.level = 0.01;
  d.adopted = true;
  EXPECT_TRUE(Contains(RenderNote(d), "raised by maximum likelihood (vertical position 1e-06 → 6.33e-05 m; "
                                      "2Δℓ = 167.7 against χ²(2) at 0.01)"))
      << RenderNote(d);
  d.adopted = false;
  EXPECT_TRUE(Contains(RenderNote(d), "the reference accuracy is kept"));
}

TEST(DecisionTest, QuantisationAndWarmUpsRenderWhatTheyWeighed) {
  Decision q;
  q.kind = DecisionKind::kQuantisationKept;
  q.subjects = {"acc_quantization.x", "acc_quantization.z"};
  q.measures = {{"acc_quantization.x", 0.00125}, {"acc_quantization.z", 0.00131}};
  q.qualifiers = {"after_the_drifts"};
  q.statistic = 68858.2;
  q.adopted = true;
  EXPECT_EQ(RenderNote(q), "the Allan fit's accelerometer quantisation (x 0.00125 m/s, z 0.00131 m/s) is in the "
                           "model: with the identified drifts the innovations' likelihood prefers it, 2Δℓ = 68858.2");
  q.adopted = false;
  q.statistic = -3.5;
  q.qualifiers = {"before_the_drifts"};
  EXPECT_TRUE(Contains(RenderNote(q), "is not in the model: with the a-priori drifts the innovations' likelihood "
                                      "is higher without it (2Δℓ = 3.5)"));
  Decision w;
  w.kind = DecisionKind::kStartExplainedByWarmUps;
  w.subjects = {"gyro_warm_up.x@516"};
  w.measures = {{"start_span_s", 120}};
  w.adopted = true;
  EXPECT_EQ(RenderNote(w), "the unit settles after power-up: model A failed only within its first 120 s, and with "
                           "its warm-ups carried (gyro_warm_up.x@516) no failure remains there and nothing is found");
}

// Every kind has a note of its own (its name in the report: ReportCodec).
TEST(DecisionTest, EveryKindHasItsOwnNote) {
  std::vector<std::string> notes;
  for (int k = 0; k <= static_cast<int>(DecisionKind::kAPrioriModel); ++k) {
    Decision d;
    d.kind = static_cast<DecisionKind>(k);
    notes.push_back(RenderNote(d));
    EXPECT_FALSE(notes.back().empty()) << k;
  }
  std::sort(notes.begin(), notes.end());
  EXPECT_EQ(std::unique(notes.begin(), notes.end()), notes.end());
}

TEST(DecisionTest, ALogKeepsNotesAndDecisionsInTheOrderMade) {
  DecisionLog log;
  log.Note("first, a note");
  log.Record(FaultTest(false));
  DecisionLog later;
  later.Record(FaultTest(true));
  later.NoteEach({"last", "notes"});
  log.Append(later);
  ASSERT_EQ(log.notes().size(), 5u);
  EXPECT_EQ(log.notes()[0], "first, a note");
  EXPECT_EQ(log.notes()[1], RenderNote(FaultTest(false)));
  EXPECT_EQ(log.notes()[2], RenderNote(FaultTest(true)));
  EXPECT_EQ(log.notes()[4], "notes");
  ASSERT_EQ(log.decisions().size(), 2u);
  EXPECT_FALSE(log.decisions()[0].adopted);
  EXPECT_TRUE(log.decisions()[1].adopted);
  EXPECT_EQ(log.decisions()[1].kind, DecisionKind::kFaultAgainstDrifts);
}

}  // namespace
}  // namespace insdiag::engine
