// hystloop-model: runs any of the project's models over a CSV file, so a user can try a model on
// their own data.
//
//   hystloop-model --model mem --forward data.csv --out y.csv            t,u     -> t,u,y
//   hystloop-model --model pi --param count=15 --param range_V=250 --inverse ref.csv  t,y_ref -> t,y_ref,u
//   hystloop-model --params-file fitted.yaml --inverse - < ref.csv
//
// Exit status: 0 done, 1 the model produced a non-finite value, 2 refused (usage, parameters,
// input file), with a message naming the file and line, or the parameter.
#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "models/csv_columns.hpp"
#include "model_registry.hpp"
#include "models/param_table.hpp"
#include "params_file.hpp"

namespace {

using namespace hystloop;
using namespace hystloop::model_tool;

constexpr const char* kTool = "hystloop-model";

struct Args {
  std::string input;
  std::string model;
  bool forward = false;
  bool inverse = false;
  std::vector<std::string> params;
  std::string params_file;
  std::string out;
};

int refuse(const std::string& message) {
  std::cerr << kTool << ": " << message << "\n";
  return kExitUsage;
}

// Assignments in the order they apply: the file first, then each --param over it.
std::vector<Assignment> collect_assignments(Args& args) {
  std::vector<Assignment> assignments;
  if (!args.params_file.empty()) {
    ParamsFile file = read_params_file(args.params_file, args.model);
    if (args.model.empty()) args.model = file.model;
    assignments = std::move(file.assignments);
  }
  for (const auto& p : args.params) assignments.push_back(split_assignment(p, "--param"));
  return assignments;
}

CsvColumns read_input(const Args& args, const std::string& name, std::span<const std::string_view> columns) {
  if (args.input == "-") return read_csv_columns(std::cin, name, columns);
  std::ifstream in(args.input);
  if (!in) throw ParameterError(name, "cannot open the input file");
  return read_csv_columns(in, name, columns);
}

// Refused input exits 2: a ParameterError (an AssignmentError, an input that cannot be opened)
// through run_tool, a params file's or a CSV's error here; anything else run_tool exits 1 on.
int transform(Args& args) try {
  std::vector<Assignment> assignments = collect_assignments(args);
  if (args.model.empty()) return refuse("give --model (one of " + model_names() + ") or --params-file");
  const ModelEntry* entry = find_model(args.model);
  if (entry == nullptr) {
    std::vector<std::string> names;
    for (const ModelEntry* m : model_registry()) names.emplace_back(m->name);
    const std::string guess = closest_name(args.model, names);
    return refuse("--model: unknown model '" + args.model + "'" +
                  (guess.empty() ? "" : "; did you mean '" + guess + "'?") + " (models: " + model_names() + ")");
  }
  if (args.inverse && !entry->has_inverse) {
    return refuse("--inverse: model " + args.model +
                  " has no inverse (a dynamic stage, not a static hysteresis map); run it --forward, or use an "
                  "invertible model (" +
                  invertible_model_names() + ") for feedforward");
  }

  std::unique_ptr<ModelRun> runner;
  try {
    runner = entry->configure(assignments);
  } catch (const AssignmentError& e) {
    return refuse(e.what());
  } catch (const ParameterError& e) {
    return refuse("model " + args.model + ": " + e.what());
  }

  const std::string name = args.input == "-" ? "<stdin>" : args.input;
  const std::string_view forward_in[] = {"t", "u"};
  const std::string_view inverse_in[] = {"t", "y_ref"};
  const std::span<const std::string_view> columns = args.forward ? forward_in : inverse_in;
  CsvColumns table = read_input(args, name, columns);
  if (entry->uses_time) require_increasing(table, 0, name);
  if (!table.ignored.empty()) {
    std::string list;
    for (const auto& c : table.ignored) list += (list.empty() ? "'" : ", '") + c + "'";
    std::cerr << kTool << ": " << name << ":" << table.header_line << ": ignoring column"
              << (table.ignored.size() > 1 ? "s " : " ") << list << " (reads '" << columns[0] << "," << columns[1]
              << "')\n";
  }

  const std::vector<double>& t = table.values[0];
  const std::vector<double>& in = table.values[1];
  const std::vector<double> result = args.forward ? runner->forward(t, in) : runner->inverse(t, in);
  for (std::size_t k = 0; k < result.size(); ++k) {
    if (!std::isfinite(result[k])) {
      std::cerr << kTool << ": " << name << ":" << table.lines[k] << ": model " << args.model << " gave a non-finite "
                << (args.forward ? "y" : "u") << " for " << columns[1] << " = " << format_number(in[k]) << "\n";
      return 1;
    }
  }

  const std::string_view forward_out[] = {"t", "u", "y"};
  const std::string_view inverse_out[] = {"t", "y_ref", "u"};
  const std::vector<double>* data[] = {&t, &in, &result};
  const std::span<const std::string_view> out_names = args.forward ? forward_out : inverse_out;
  if (args.out.empty()) {
    write_csv_columns(std::cout, out_names, data);
    std::cout.flush();
    if (!std::cout) return refuse("cannot write to standard output");
    return 0;
  }
  std::ofstream out(args.out);
  if (out) write_csv_columns(out, out_names, data);
  out.close();
  if (!out) return refuse(args.out + ": cannot write the output file");
  return 0;
} catch (const ParamsFileError& e) {
  return refuse(e.what());
} catch (const CsvError& e) {
  return refuse(e.what());
}

int run(int argc, char** argv) {
  CLI::App app{
      "Run a hysteresis model over a CSV file (header row, comma separated, SI units).\n"
      "--forward reads columns t,u [s, V] and writes t,u,y [m]; --inverse reads t,y_ref [s, m] and writes t,y_ref,u "
      "[V].\n"
      "The first row sets the initial state (the model's reset at that point); other columns are ignored."};
  app.footer(models_help() +
             "\nExamples:\n"
             "  hystloop-model --model mem --forward data.csv --out y.csv\n"
             "  hystloop-model --model pi --param count=15 --param range_V=250 --inverse ref.csv\n"
             "  hystloop-model --params-file fitted.yaml --inverse - < ref.csv   (YAML from hystloop-identify --out)\n"
             "Exit status: 0 done, 1 the model gave a non-finite value, 2 refused (usage, parameters, input).");
  Args args;
  app.add_option("input", args.input, "CSV file, or - for standard input")->required();
  app.add_option("--model", args.model, "model: " + model_names(" | ") + " (default: the params file's section)");
  auto* fwd = app.add_flag("--forward", args.forward, "u -> y: read t,u, write t,u,y");
  auto* inv = app.add_flag("--inverse", args.inverse, "y_ref -> u (feedforward): read t,y_ref, write t,y_ref,u");
  fwd->excludes(inv);
  app.add_option("--param", args.params, "NAME=VALUE, repeatable; overrides the params file (names below)");
  app.add_option("--params-file", args.params_file, "YAML as hystloop-identify --out writes it (model: {name: value})");
  app.add_option("--out", args.out, "output CSV file (default: standard output)");
  if (const auto exit_code = parse_cli(app, argc, argv)) return *exit_code;
  if (!args.forward && !args.inverse) return refuse("choose --forward (t,u -> y) or --inverse (t,y_ref -> u)");
  return transform(args);
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool(kTool, [&] { return run(argc, argv); });
}
