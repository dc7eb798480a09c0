// How the uncertainty module quotes a budget's model in its messages (issue #37): once, cut to
// 120 bytes around the place the message is about (metro/core/terminal_text.hpp, Excerpt), at
// the file:line:column of that place in the budget. A 1 MB model was echoed whole, twice, on
// one line. Private to the uncertainty module.
#pragma once

#include <string>

#include "metro/core/status.hpp"
#include "metro/uncertainty/budget.hpp"

namespace metro::internal {

// `model_error` (from MeasurementModel::FromExpression or CheckModelUnits: column = the 1-based
// byte of the model it is about, 0 for the whole model) as an error of the budget's file:
// "model '<excerpt around that byte>' <what>" at the line and column of that byte in the file
// (of the model's opening quote for the whole model; no line for a budget built in code).
// `what` follows the quote with a space when it reads on ("uses 'z', ...", "evaluates to ...",
// "is NaN ..."), a comma before
// "column N: ..." and a colon otherwise.
Error ModelError(const Budget& budget, const Error& model_error);

// An error about the whole model: "model '<excerpt>' <what>" at the model's position.
Error ModelError(const Budget& budget, const std::string& what);

// The model quoted for a message that has no position (a warning): "'<excerpt>'".
std::string QuotedModel(const Budget& budget);

}  // namespace metro::internal
