// The grammar of a budget's model expression (docs/budget-format.md, "Model"), read once into
// a syntax tree that both the exact derivatives (symbolic_model.cpp, GiNaC) and the unit check
// (model_units.cpp, UDUNITS-2) walk. It is muparser's grammar, the evaluator's
// (MeasurementModel, model.hpp), lowest precedence first:
//
//   ternary  = or [ '?' ternary ':' ternary ]
//   or       = and { '||' and }
//   and      = compare { '&&' compare }
//   compare  = additive { ('==' | '!=' | '<=' | '>=' | '<' | '>') additive }
//   additive = product { ('+' | '-') product }
//   product  = unary { ('*' | '/') unary }
//   unary    = ('-' | '+') unary | power      signs bind less tightly than ^: -2^2 = -4
//   power    = primary [ '^' unary ]          right-associative, signed: 2^3^2 = 2^9, 2^-1
//   primary  = number | name | name '(' [ ternary { ',' ternary } ] ')' | '(' ternary ')'
//   number   = digits [ '.' digits ] [ ('e' | 'E') [ '+' | '-' ] digits ], or '.' digits ...
//
// Chains of one level (a - b + c, a < b == 1) are left-associative. Space is any byte from 1
// to 32, as muparser skips it. A name is an input, else the constant pi (metro defines it for
// muparser unless an input is called pi), _pi or _e. The functions (ModelFunction) are
// muparser's: sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh exp sqrt log (the
// natural logarithm, like ln) ln log10 log2 atan2(y, x) abs sign rint, and min max sum avg of
// one or more arguments.
//
// Reading nests at most kMaxModelDepth levels (each '?:' operand, parenthesis, argument and
// sign is a level), so a hostile model cannot exhaust the stack; chains are flat (one node),
// so a long sum is not deep. Private to the uncertainty module.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {
namespace internal {

constexpr int kMaxModelDepth = 256;

// pi (and _pi) and _e in double, where a reader of the tree evaluates in double.
constexpr double kModelPi = 3.14159265358979323846;
constexpr double kModelE = 2.71828182845904523536;

// The binary operators of a chain, by level: or, and, comparisons, + -, * /.
enum class ModelOperator {
  kOr,
  kAnd,
  kEqual,
  kNotEqual,
  kLessEqual,
  kGreaterEqual,
  kLess,
  kGreater,
  kAdd,
  kSubtract,
  kMultiply,
  kDivide
};

enum class ModelFunction {
  kSin,
  kCos,
  kTan,
  kAsin,
  kAcos,
  kAtan,
  kSinh,
  kCosh,
  kTanh,
  kAsinh,
  kAcosh,
  kAtanh,
  kExp,
  kSqrt,
  kLog,  // muparser's log is the natural logarithm.
  kLn,
  kLog10,
  kLog2,
  kAtan2,  // atan2(y, x).
  kAbs,
  kSign,
  kRint,  // muparser's: floor(x + 0.5), halves up (not the C library's ties to even).
  kMin,
  kMax,
  kSum,
  kAvg
};

struct ModelNode {
  enum class Kind {
    kNumber,  // `text` is the literal as written, `number` its double value (strtod).
    kInput,   // names[input].
    kPi,      // pi or _pi.
    kE,       // _e.
    kSign,    // children {operand}; `negative` for '-'.
    kPower,   // children {base, exponent}.
    kChain,   // children {x0, x1, ...}: x0 ops[0] x1 ops[1] x2 ..., from the left.
    kIf,      // children {condition, then, else}.
    kCall,    // children: the arguments of `function` (`text` is its name).
  };
  Kind kind = Kind::kNumber;
  // Byte offsets into the model (0-based). [begin, end) is the node's text from its first
  // token to its last, its own parentheses included. `at` is where a message about the node
  // points: the sign, the '^', the '?', the function's name, else `begin`. `lead` is where its
  // reading began, before any space: the end of the token before it (0 for the first).
  size_t begin = 0;
  size_t end = 0;
  size_t at = 0;
  size_t lead = 0;
  std::vector<size_t> children;    // Indices into ModelSyntax::nodes.
  std::vector<ModelOperator> ops;  // kChain: ops[k] joins children[k] and children[k + 1],
  std::vector<size_t> op_at;       // written at byte op_at[k].
  std::string text;                // kNumber: the literal; kCall: the function's name.
  double number = 0.0;             // kNumber.
  size_t input = 0;                // kInput.
  bool negative = false;           // kSign.
  ModelFunction function = ModelFunction::kSin;  // kCall.
};

struct ModelSyntax {
  std::vector<ModelNode> nodes;  // Every node after its children: the root is the last.
  size_t root() const { return nodes.size() - 1; }
};

// The model `text` over inputs `names`. Errors: "column N: <what was expected or found>" with
// Error::column = N (1-based byte): a token out of place, an unknown name or function, a
// function with the wrong number of arguments, nesting beyond kMaxModelDepth.
Result<ModelSyntax> ParseModel(const std::string& text, const std::vector<std::string>& names);

// The operator as written: "||", "<=", "+", ...
const char* ModelOperatorText(ModelOperator op);

// The double meaning of each operator and function as muparser computes it: comparisons and
// && || give 1 or 0 (a nonzero operand is true), min/max are fmin/fmax, sign(0) = 0.
// Precondition: `args` has the function's arity (ParseModel checks it).
double ApplyOperator(ModelOperator op, double a, double b);
double ApplyFunction(ModelFunction function, const std::vector<double>& args);

// f(x) in double from the tree (x[names.size()]): what muparser computes, up to rounding.
double EvaluateModel(const ModelSyntax& syntax, const double* x);

}  // namespace internal
}  // namespace metro
