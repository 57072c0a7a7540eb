// The FMI 2.0 co-simulation functions (fmi2.hpp) on fmi::Instance. No
// exception crosses the C boundary: each function catches everything,
// logs the message through the importer's logger and returns fmi2Error.
#include <cstdarg>
#include <cstring>
#include <memory>
#include <string>

#include "framework/fmi/fmi2.hpp"
#include "framework/fmi/instance.hpp"

namespace {

using pneumo::fmi::Instance;

struct Component {
  std::string name;
  fmi2CallbackLogger logger = nullptr;
  fmi2ComponentEnvironment environment = nullptr;
  bool logging = false;
  fmi2Status last_step = fmi2OK;
  std::unique_ptr<Instance> instance;

  // The logger's message is a printf format: a '%' in the text is doubled.
  void log(fmi2Status status, const char* category, const std::string& message) const {
    if (!logger || (!logging && status == fmi2OK)) return;
    std::string text;
    for (char c : message) text += c == '%' ? std::string("%%") : std::string(1, c);
    logger(environment, name.c_str(), status, category, text.c_str());
  }
};

Component* as_component(fmi2Component c) { return static_cast<Component*>(c); }

// Runs f on the instance; every exception becomes fmi2Error with its message.
template <class F>
fmi2Status guarded(fmi2Component c, const char* what, F&& f) {
  if (!c) return fmi2Error;
  Component& comp = *as_component(c);
  try {
    f(*comp.instance);
    return fmi2OK;
  } catch (const std::exception& e) {
    comp.log(fmi2Error, "logStatusError", std::string(what) + ": " + e.what());
  } catch (...) {
    comp.log(fmi2Error, "logStatusError", std::string(what) + ": unknown error");
  }
  return fmi2Error;
}

fmi2Status unsupported(fmi2Component c, const char* what) {
  if (c) as_component(c)->log(fmi2Error, "logStatusError", std::string(what) + " is not supported by this FMU");
  return fmi2Error;
}

// "file:///a/b", "file://localhost/a/b" or "file:/a/b" -> "/a/b", %XX decoded.
std::string resource_path(const char* uri) {
  std::string s = uri ? uri : "";
  if (s.rfind("file://localhost/", 0) == 0) s = s.substr(16);
  else if (s.rfind("file:///", 0) == 0) s = s.substr(7);
  else if (s.rfind("file:/", 0) == 0) s = s.substr(5);
  else throw std::runtime_error("fmuResourceLocation '" + s + "' is not a file: URI");
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size()) {
      out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  return out;
}

}  // namespace

extern "C" {

const char* fmi2GetTypesPlatform(void) { return "default"; }
const char* fmi2GetVersion(void) { return "2.0"; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t, const fmi2String[]) {
  if (!c) return fmi2Error;
  as_component(c)->logging = loggingOn == fmi2True;
  return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions, fmi2Boolean,
                              fmi2Boolean loggingOn) {
  Component* comp = nullptr;
  try {
    comp = new Component;
    comp->name = instanceName ? instanceName : "";
    if (functions) comp->logger = functions->logger, comp->environment = functions->componentEnvironment;
    comp->logging = loggingOn == fmi2True;
    if (fmuType != fmi2CoSimulation) throw std::runtime_error("this FMU is for co-simulation only");
    Component* self = comp;
    comp->instance = std::make_unique<Instance>(resource_path(fmuResourceLocation), fmuGUID ? fmuGUID : "",
                                                [self](const char* category, const std::string& message) {
                                                  self->log(fmi2OK, category, message);
                                                });
    return comp;
  } catch (const std::exception& e) {
    if (comp) comp->log(fmi2Error, "logStatusError", std::string("fmi2Instantiate: ") + e.what());
  } catch (...) {
  }
  delete comp;
  return nullptr;
}

void fmi2FreeInstance(fmi2Component c) { delete as_component(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean, fmi2Real, fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
  return guarded(c, "fmi2SetupExperiment",
                 [&](Instance& i) { i.setup_experiment(startTime, stopTimeDefined == fmi2True, stopTime); });
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  return guarded(c, "fmi2EnterInitializationMode", [](Instance& i) { i.enter_initialization(); });
}
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  return guarded(c, "fmi2ExitInitializationMode", [](Instance& i) { i.exit_initialization(); });
}
fmi2Status fmi2Terminate(fmi2Component c) {
  return guarded(c, "fmi2Terminate", [](Instance& i) { i.terminate(); });
}
fmi2Status fmi2Reset(fmi2Component c) {
  return guarded(c, "fmi2Reset", [](Instance& i) { i.reset(); });
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
  return guarded(c, "fmi2GetReal", [&](Instance& i) {
    for (size_t k = 0; k < nvr; ++k) value[k] = i.get(vr[k]);
  });
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
  return guarded(c, "fmi2SetReal", [&](Instance& i) {
    for (size_t k = 0; k < nvr; ++k) i.set(vr[k], value[k]);
  });
}

// The FMU has Real variables only.
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2Integer[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetInteger (no Integer variables)");
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2Boolean[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetBoolean (no Boolean variables)");
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference[], size_t nvr, fmi2String[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetString (no String variables)");
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Integer[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetInteger (no Integer variables)");
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Boolean[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetBoolean (no Boolean variables)");
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2String[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetString (no String variables)");
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate*) { return unsupported(c, "fmi2GetFMUstate"); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate) { return unsupported(c, "fmi2SetFMUstate"); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate*) { return unsupported(c, "fmi2FreeFMUstate"); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate, size_t*) {
  return unsupported(c, "fmi2SerializedFMUstateSize");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate, fmi2Byte[], size_t) {
  return unsupported(c, "fmi2SerializeFMUstate");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte[], size_t, fmi2FMUstate*) {
  return unsupported(c, "fmi2DeSerializeFMUstate");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference[], size_t,
                                        const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]) {
  return unsupported(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Integer[],
                                       const fmi2Real[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2SetRealInputDerivatives (canInterpolateInputs is false)");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t nvr, const fmi2Integer[],
                                        fmi2Real[]) {
  return nvr == 0 ? fmi2OK : unsupported(c, "fmi2GetRealOutputDerivatives (maxOutputDerivativeOrder is 0)");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean) {
  const fmi2Status s = guarded(c, "fmi2DoStep", [&](Instance& i) { i.do_step(currentCommunicationPoint, communicationStepSize); });
  if (c) as_component(c)->last_step = s;
  return s;
}

// Steps are synchronous: there is never one to cancel.
fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep (steps are synchronous)"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
  if (!c || s != fmi2DoStepStatus) return unsupported(c, "fmi2GetStatus of this kind");
  *value = as_component(c)->last_step;
  return fmi2OK;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
  if (!c || s != fmi2LastSuccessfulTime) return unsupported(c, "fmi2GetRealStatus of this kind");
  *value = as_component(c)->instance->time();
  return fmi2OK;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind, fmi2Integer*) {
  return unsupported(c, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
  if (!c || s != fmi2Terminated) return unsupported(c, "fmi2GetBooleanStatus of this kind");
  *value = fmi2False;
  return fmi2OK;
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind, fmi2String*) {
  return unsupported(c, "fmi2GetStringStatus");
}

}  // extern "C"
