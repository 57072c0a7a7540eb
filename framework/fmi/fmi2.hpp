// The FMI 2.0 C interface (Functional Mock-up Interface 2.0.x, sections 2.1
// and 4): its types and the functions a co-simulation FMU exports, declared
// here from the specification's text. Names and signatures are fixed by the
// standard; an importer finds them with dlsym.
#pragma once

#include <cstddef>

extern "C" {

typedef void* fmi2Component;
typedef void* fmi2ComponentEnvironment;
typedef void* fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char* fmi2String;
typedef char fmi2Byte;

#define fmi2True 1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum { fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated } fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String instanceName, fmi2Status status,
                                   fmi2String category, fmi2String message, ...);
typedef void* (*fmi2CallbackAllocateMemory)(size_t nobj, size_t size);
typedef void (*fmi2CallbackFreeMemory)(void* obj);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

typedef struct {
  const fmi2CallbackLogger logger;
  const fmi2CallbackAllocateMemory allocateMemory;
  const fmi2CallbackFreeMemory freeMemory;
  const fmi2StepFinished stepFinished;
  const fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

#define PNEUMO_FMI2_EXPORT __attribute__((visibility("default")))

// Common functions.
PNEUMO_FMI2_EXPORT const char* fmi2GetTypesPlatform(void);
PNEUMO_FMI2_EXPORT const char* fmi2GetVersion(void);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component, fmi2Boolean loggingOn, size_t nCategories,
                                                  const fmi2String categories[]);
PNEUMO_FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                                 fmi2String fmuResourceLocation,
                                                 const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                                                 fmi2Boolean loggingOn);
PNEUMO_FMI2_EXPORT void fmi2FreeInstance(fmi2Component);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                                  fmi2Real startTime, fmi2Boolean stopTimeDefined,
                                                  fmi2Real stopTime);
PNEUMO_FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component);
PNEUMO_FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component);
PNEUMO_FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component);
PNEUMO_FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                          fmi2Real value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetInteger(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                             fmi2Integer value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetBoolean(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                             fmi2Boolean value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetString(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                            fmi2String value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                          const fmi2Real value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetInteger(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                             const fmi2Integer value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetBoolean(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                             const fmi2Boolean value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetString(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                            const fmi2String value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component, fmi2FMUstate*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component, fmi2FMUstate);
PNEUMO_FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component, fmi2FMUstate*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component, fmi2FMUstate, size_t*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
PNEUMO_FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component, const fmi2Byte[], size_t, fmi2FMUstate*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component, const fmi2ValueReference vUnknown_ref[],
                                                           size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                                           size_t nKnown, const fmi2Real dvKnown[],
                                                           fmi2Real dvUnknown[]);

// Co-simulation functions.
PNEUMO_FMI2_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                                          const fmi2Integer order[], const fmi2Real value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component, const fmi2ValueReference vr[], size_t nvr,
                                                           const fmi2Integer order[], fmi2Real value[]);
PNEUMO_FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component, fmi2Real currentCommunicationPoint,
                                         fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint);
PNEUMO_FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component, const fmi2StatusKind, fmi2Status*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component, const fmi2StatusKind, fmi2Real*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component, const fmi2StatusKind, fmi2Integer*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component, const fmi2StatusKind, fmi2Boolean*);
PNEUMO_FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component, const fmi2StatusKind, fmi2String*);
}
