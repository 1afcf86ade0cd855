/*
 * altfusion's FMI 2.0 shim: the binaries/linux64/<model>.so of every FMU, in front of
 * pythonfmu 0.7.0's library (shipped beside it as PYTHONFMU_LIBRARY). Our own code: it
 * forwards every FMI 2.0 co-simulation function to pythonfmu and adds what a host that uses
 * only the standard needs (see DEVELOPERS.md, "The native shim"):
 *
 *  - Resource URIs: file:/p, file:///p, file://localhost/p (and percent-escapes) are all
 *    handed to pythonfmu as file:///p, the only form it reads.
 *  - Clean exit and unload: pythonfmu releases its static Python state twice when it is
 *    unloaded or the process exits (C++ static destructor, then its unload hook) unless
 *    finalizePythonInterpreter ran first. Once pythonfmu is loaded, the shim registers a
 *    handler that calls the finalizer: handlers run in reverse order of registration, at exit
 *    or when the host unloads the shim, so it runs before pythonfmu's static destructors.
 *    In a Python host both unload with the host's dlclose (each unload and reload would
 *    otherwise keep ~0.4 MB). Calling the finalizer again is harmless.
 *  - Teardown in any order. pythonfmu's finalizer finalizes the interpreter if pythonfmu
 *    started it, and a host may tear its instances down in its own exit handlers, which run
 *    after ours (OMSimulator's) or after a Python host finalized its interpreter. So, in a host
 *    without a running Python (a C host), the shim starts the interpreter itself before
 *    pythonfmu loads (pythonfmu then never owns it and its finalizer touches no Python) and
 *    finalizes it only once the host has freed every instance of every shim in the process
 *    (a count shared through the interpreter, SHARED_COUNT) and exit has begun; an instance
 *    the host never frees keeps it alive to the end. The interpreter cannot be started twice
 *    (numpy): the shim that started it loads pythonfmu with RTLD_NODELETE and pins itself the
 *    same way. Every FMI call made once the interpreter has been finalized (by a Python host,
 *    or by us after the last free) touches no Python: fmi2Terminate, fmi2FreeInstance and
 *    fmi2FreeFMUstate succeed, every other call returns fmi2Error saying why.
 *  - Failures reach the host: pythonfmu is instantiated with logging on; messages of status
 *    fmi2Warning or worse reach the host's logger whatever loggingOn says, the others when the
 *    host asked for them (loggingOn, fmi2SetDebugLogging and its categories). Every call
 *    returns the worst error logged during it, so an error the Python side can only log
 *    (a refused FMU state, a failed initialization) returns fmi2Error; a warning (a rejected
 *    sample, a replay without a log) reaches the logger only, and the call returns fmi2OK:
 *    OMSimulator's master stops a simulation at any doStep status but fmi2OK. A state refused by
 *    fmi2DeSerializeFMUstate (the Python object carries a `reason`) is freed and returns
 *    fmi2Error with that reason.
 *  - Values and steps straight to the slave: while an instance steps (after
 *    fmi2ExitInitializationMode), fmi2Get/Set of inputs and outputs read and write the core's
 *    attributes and fmi2DoStep calls the slave's do_step, without pythonfmu's bridge (see
 *    "direct access" below).
 *  - The GUID is checked: fmi2Instantiate with a GUID other than the one the slave computes
 *    from its interface (altfusion.fmi.guid, the one in this FMU's modelDescription.xml)
 *    returns NULL, saying both: the host read another build's description, whose value
 *    references may name other variables (pythonfmu does not look at the GUID).
 *  - Instances are reused: fmi2FreeInstance resets a healthy instance (fmi2Reset) and keeps
 *    up to POOL_SIZE of them; fmi2Instantiate of the same GUID and resources hands one back.
 *    pythonfmu re-executes the slave script at each fmi2Instantiate and keeps ~1 kB per call.
 *    Pooled instances are freed when the shim is unloaded (or at exit, if Python still runs).
 *
 * Built by build_fmu.py with the system compiler: cc -shared -fPIC -Wl,-z,now (no Python
 * headers: the few Python C-API functions used are declared below and, like pythonfmu's,
 * resolved from the Python already in the process).
 */
#define _GNU_SOURCE
#include <ctype.h>
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <wchar.h>

/* glibc >= 2.34 versions the dl* functions anew; bind the x86-64 baseline versions so the
 * shim needs no newer glibc than pythonfmu's library (2.32). */
#if defined(__x86_64__) && defined(__GLIBC__)
__asm__(".symver dlopen,dlopen@GLIBC_2.2.5");
__asm__(".symver dlsym,dlsym@GLIBC_2.2.5");
__asm__(".symver dladdr,dladdr@GLIBC_2.2.5");
__asm__(".symver dlerror,dlerror@GLIBC_2.2.5");
__asm__(".symver dlclose,dlclose@GLIBC_2.2.5");
#endif

#ifndef PYTHONFMU_LIBRARY
#define PYTHONFMU_LIBRARY "pythonfmu-export.so"
#endif
#define POOL_SIZE 4
#define MAX_CATEGORIES 32
#define EXPORT __attribute__((visibility("default")))

/* ---------------------------------------------------------------- FMI 2.0 types (standard) */
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
typedef enum {
    fmi2DoStepStatus, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated
} fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef void* (*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void*);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);
typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2StepFinished stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

/* The functions pythonfmu exports besides the two answered here (fmi2GetTypesPlatform,
 * fmi2GetVersion), with their standard prototypes; the shim exports each of them. */
EXPORT fmi2Component fmi2Instantiate(fmi2String, fmi2Type, fmi2String, fmi2String,
                                     const fmi2CallbackFunctions*, fmi2Boolean, fmi2Boolean);
EXPORT void fmi2FreeInstance(fmi2Component);
EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component, fmi2Boolean, size_t, const fmi2String[]);
EXPORT fmi2Status fmi2SetupExperiment(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real,
                                      fmi2Boolean, fmi2Real);
EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component);
EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component);
EXPORT fmi2Status fmi2Terminate(fmi2Component);
EXPORT fmi2Status fmi2Reset(fmi2Component);
EXPORT fmi2Status fmi2GetReal(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
EXPORT fmi2Status fmi2GetInteger(fmi2Component, const fmi2ValueReference[], size_t,
                                 fmi2Integer[]);
EXPORT fmi2Status fmi2GetBoolean(fmi2Component, const fmi2ValueReference[], size_t,
                                 fmi2Boolean[]);
EXPORT fmi2Status fmi2GetString(fmi2Component, const fmi2ValueReference[], size_t, fmi2String[]);
EXPORT fmi2Status fmi2SetReal(fmi2Component, const fmi2ValueReference[], size_t,
                              const fmi2Real[]);
EXPORT fmi2Status fmi2SetInteger(fmi2Component, const fmi2ValueReference[], size_t,
                                 const fmi2Integer[]);
EXPORT fmi2Status fmi2SetBoolean(fmi2Component, const fmi2ValueReference[], size_t,
                                 const fmi2Boolean[]);
EXPORT fmi2Status fmi2SetString(fmi2Component, const fmi2ValueReference[], size_t,
                                const fmi2String[]);
EXPORT fmi2Status fmi2GetFMUstate(fmi2Component, fmi2FMUstate*);
EXPORT fmi2Status fmi2SetFMUstate(fmi2Component, fmi2FMUstate);
EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component, fmi2FMUstate*);
EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component, fmi2FMUstate, size_t*);
EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component, const fmi2Byte[], size_t,
                                          fmi2FMUstate*);
EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component, const fmi2ValueReference[], size_t,
                                               const fmi2ValueReference[], size_t,
                                               const fmi2Real[], fmi2Real[]);
EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component, const fmi2ValueReference[], size_t,
                                              const fmi2Integer[], const fmi2Real[]);
EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component, const fmi2ValueReference[], size_t,
                                               const fmi2Integer[], fmi2Real[]);
EXPORT fmi2Status fmi2DoStep(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
EXPORT fmi2Status fmi2CancelStep(fmi2Component);
EXPORT fmi2Status fmi2GetStatus(fmi2Component, const fmi2StatusKind, fmi2Status*);
EXPORT fmi2Status fmi2GetRealStatus(fmi2Component, const fmi2StatusKind, fmi2Real*);
EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component, const fmi2StatusKind, fmi2Integer*);
EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component, const fmi2StatusKind, fmi2Boolean*);
EXPORT fmi2Status fmi2GetStringStatus(fmi2Component, const fmi2StatusKind, fmi2String*);
EXPORT void finalizePythonInterpreter(void);

/* ---------------------------------------------------------------- Python C-API (stable ABI)
 * Resolved from the host process, as pythonfmu's library resolves its own (no headers). The
 * shim is linked with -z now: in a process without Python it does not load at all, the
 * loader naming the missing symbol, as pythonfmu's library does. */
typedef struct PyObject PyObject;
typedef struct PyThreadState PyThreadState;
typedef int PyGILState_STATE;
extern int Py_IsInitialized(void);
extern void Py_SetProgramName(const wchar_t*);
extern void Py_InitializeEx(int);
extern int Py_FinalizeEx(void);
extern PyThreadState* PyEval_SaveThread(void);
extern void PyEval_RestoreThread(PyThreadState*);
extern PyObject* PyCapsule_New(void*, const char*, void (*)(PyObject*));
extern void* PyCapsule_GetPointer(PyObject*, const char*);
extern PyObject* PySys_GetObject(const char*);
extern PyObject* PyImport_ImportModule(const char*);
extern int PySys_SetObject(const char*, PyObject*);
extern PyGILState_STATE PyGILState_Ensure(void);
extern PyThreadState* PyGILState_GetThisThreadState(void);
extern void PyGILState_Release(PyGILState_STATE);
extern PyObject* PyObject_GetAttrString(PyObject*, const char*);
extern const char* PyUnicode_AsUTF8(PyObject*);
extern void Py_DecRef(PyObject*);
extern void PyErr_Clear(void);
extern PyObject* PyErr_Occurred(void);
extern void PyErr_Fetch(PyObject**, PyObject**, PyObject**);
extern void Py_IncRef(PyObject*);
extern PyObject* Py_BuildValue(const char*, ...);
extern PyObject* PyObject_GetAttr(PyObject*, PyObject*);
extern int PyObject_SetAttr(PyObject*, PyObject*, PyObject*);
extern PyObject* PyObject_Str(PyObject*);
extern int PyObject_IsTrue(PyObject*);
extern PyObject* PyObject_CallFunctionObjArgs(PyObject*, ...);
extern PyObject* PyObject_CallMethodObjArgs(PyObject*, PyObject*, ...);
extern PyObject* PyUnicode_InternFromString(const char*);
extern PyObject* PyFloat_FromDouble(double);
extern double PyFloat_AsDouble(PyObject*);
extern PyObject* PyLong_FromLong(long);
extern PyObject* PyLong_FromUnsignedLong(unsigned long);
extern long PyLong_AsLong(PyObject*);
extern PyObject* PyBool_FromLong(long);
extern long PyTuple_Size(PyObject*);
extern PyObject* PyTuple_GetItem(PyObject*, long);
extern long PyUnicode_GetLength(PyObject*);
extern long PyList_Size(PyObject*);
extern PyObject* PyList_GetItem(PyObject*, long);
extern PyObject* PyList_New(long);
extern int PyList_SetItem(PyObject*, long, PyObject*);
extern int PyList_SetSlice(PyObject*, long, long, PyObject*);
extern PyObject* PyDict_New(void);
extern PyObject* PyDict_GetItem(PyObject*, PyObject*);
extern int PyDict_SetItem(PyObject*, PyObject*, PyObject*);
extern int PyDict_DelItem(PyObject*, PyObject*);

#define FORWARDED(X) \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment) \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate) X(fmi2Reset) \
    X(fmi2GetReal) X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) \
    X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString) \
    X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize) \
    X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative) \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep) \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) \
    X(fmi2GetBooleanStatus) X(fmi2GetStringStatus)

#define MEMBER(name) __typeof__(name)* name;
static struct { FORWARDED(MEMBER) void (*finalize)(void); } pythonfmu;

/* ---------------------------------------------------------------- instances */
enum { REAL, INTEGER, BOOLEAN, STRING, KINDS };   /* the FMI types of direct access */
enum { CORE, PARAMETERS, SLAVE, OWNERS };   /* whose attribute a value is */
enum { READ, WRITE };

typedef struct Instance {
    fmi2Component inner;                 /* pythonfmu's instance */
    fmi2CallbackFunctions host;          /* the host's callbacks (its logger, environment) */
    fmi2CallbackFunctions own;           /* what pythonfmu got: our logger, this instance */
    char* name;                          /* the host's instance name */
    char* guid;
    char* resources;                     /* the decoded resource folder */
    fmi2Type type;
    int logging;                         /* the host asked for messages below fmi2Warning */
    size_t n_categories;                 /* ... of these categories only (0: all) */
    char* categories[MAX_CATEGORIES];
    fmi2Status worst;                    /* the worst status logged during the current call */
    int broken;                          /* a call returned fmi2Fatal: never reused */
    double last_successful;              /* fmi2LastSuccessfulTime (NaN before a doStep) */
    /* direct access (see there): */
    PyObject* slave;                     /* pythonfmu's slave object (a reference), or NULL */
    PyObject* tables;                    /* its _native_names(): what `names` borrows from */
    PyObject** names[2][KINDS];          /* [read/write][type][vr]: the attribute or NULL */
    unsigned char* owners[2][KINDS];     /* ... of whom (CORE, PARAMETERS, SLAVE) */
    size_t n_names[2][KINDS];
    PyObject* strings;                   /* the values of the last direct fmi2GetString */
    PyObject* log_queue;                 /* the slave's list of messages, pythonfmu's */
    int direct;                          /* stepping: values and steps go straight to it */
} Instance;

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static int load_state;                   /* 0: not tried, 1: loaded, -1: failed */
static char load_error[4400];
static Instance* pool[POOL_SIZE];
static size_t pooled;

static char* copy_string(const char* text) {
    return text ? strdup(text) : NULL;
}

static fmi2Status worse(fmi2Status a, fmi2Status b) {
    if (a == fmi2Pending || b == fmi2Pending) return a == fmi2Pending ? a : b;
    return a > b ? a : b;
}

static void clear_categories(Instance* inst) {
    for (size_t i = 0; i < inst->n_categories; i++) free(inst->categories[i]);
    inst->n_categories = 0;
}

static void drop_slave(Instance* inst);

static void destroy(Instance* inst) {
    drop_slave(inst);
    clear_categories(inst);
    free(inst->name);
    free(inst->guid);
    free(inst->resources);
    free(inst);
}

/* ---------------------------------------------------------------- logging */
static int wanted(const Instance* inst, fmi2Status status, fmi2String category) {
    if (status != fmi2OK && status != fmi2Pending) return 1;
    if (!inst->logging) return 0;
    if (inst->n_categories == 0) return 1;
    for (size_t i = 0; i < inst->n_categories; i++)
        if (category && strcmp(category, inst->categories[i]) == 0) return 1;
    return 0;
}

/* Hand `text` (already formatted) to the host's logger, '%' escaped: the host formats it. */
static void to_host(const Instance* inst, fmi2Status status, fmi2String category,
                    const char* text) {
    if (!inst->host.logger || !wanted(inst, status, category)) return;
    size_t percents = 0;
    for (const char* p = text; *p; p++) percents += *p == '%';
    char* escaped = malloc(strlen(text) + percents + 1);
    if (!escaped) return;
    char* out = escaped;
    for (const char* p = text; *p; p++) {
        *out++ = *p;
        if (*p == '%') *out++ = '%';
    }
    *out = '\0';
    inst->host.logger(inst->host.componentEnvironment, inst->name ? inst->name : "",
                      status, category ? category : "", escaped);
    free(escaped);
}

static void log_own(Instance* inst, fmi2Status status, const char* format, ...) {
    char text[2048];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    inst->worst = worse(inst->worst, status);
    const char* category = status >= fmi2Error ? "logStatusError" : "logAll";
    to_host(inst, status, status == fmi2Fatal ? "logStatusFatal" : category, text);
}

/* The logger pythonfmu calls: format the message, remember the worst status, pass it on. */
static void shim_logger(fmi2ComponentEnvironment env, fmi2String instance_name,
                        fmi2Status status, fmi2String category, fmi2String message, ...) {
    (void)instance_name;   /* pythonfmu's copy; a reused instance has a new host name */
    Instance* inst = env;
    if (!inst || !message) return;
    inst->worst = worse(inst->worst, status);
    va_list args;
    va_start(args, message);
    va_list again;
    va_copy(again, args);
    int length = vsnprintf(NULL, 0, message, args);
    va_end(args);
    char* text = length >= 0 ? malloc((size_t)length + 1) : NULL;
    if (text) {
        vsnprintf(text, (size_t)length + 1, message, again);
        to_host(inst, status, category, text);
        free(text);
    }
    va_end(again);
}

/* ---------------------------------------------------------------- the interpreter */
/* The instances the host holds, over every shim in the process, and whether the exit of the
 * shim that started the interpreter has begun: that shim finalizes the interpreter when both
 * say the host is done. Shims of other FMUs (other copies of this library) find it through
 * the interpreter, as a capsule in `sys` named SHARED_COUNT. */
typedef struct {
    pthread_mutex_t lock;
    long held;
    int exiting;
    void (*finalize)(void);       /* the starting shim's finalize_interpreter */
} SharedCount;
#define SHARED_COUNT "_altfusion_fmi2_shim_instances_v1"

static SharedCount own_count = {PTHREAD_MUTEX_INITIALIZER, 0, 0, NULL};
static SharedCount* shared;       /* &own_count in the shim that started Python, NULL in a
                                   * Python host (the host finalizes its own interpreter) */
static long held_here;            /* the instances of this library the host holds */
static int released;              /* release_pythonfmu ran: freed instances are not pooled */
static int saw_python;            /* the interpreter ran once: if it no longer does, it was
                                   * finalized and cannot be started again */

static int python_alive(void) {
    return Py_IsInitialized();
}

/* Free pythonfmu's instance behind `inst` (unless it went with the interpreter), then ours. */
static void discard(Instance* inst) {
    if (python_alive()) pythonfmu.fmi2FreeInstance(inst->inner);
    destroy(inst);
}

#define FINALIZED "the Python interpreter of this process has been finalized, and this call " \
    "needs it"

/* The interpreter this shim starts lives in a thread of its own, which starts it and, when
 * asked, finalizes it: Python finalizes cleanly only in the thread that started it or one
 * holding no thread state, and hosts call FMUs from worker threads (OMSimulator) but run
 * their exit handlers in the main thread. */
static pthread_mutex_t interpreter_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t interpreter_changed = PTHREAD_COND_INITIALIZER;
enum { NOT_STARTED, RUNNING, FINALIZE, FINALIZED_NOW };
static int interpreter_phase = NOT_STARTED;
static pthread_t interpreter_thread;
static pid_t interpreter_process;   /* a forked child has no interpreter thread: it never
                                     * finalizes */

static void set_phase(int phase) {
    pthread_mutex_lock(&interpreter_lock);
    interpreter_phase = phase;
    pthread_cond_broadcast(&interpreter_changed);
    pthread_mutex_unlock(&interpreter_lock);
}

static void wait_for_phase(int phase) {
    pthread_mutex_lock(&interpreter_lock);
    while (interpreter_phase != phase) pthread_cond_wait(&interpreter_changed, &interpreter_lock);
    pthread_mutex_unlock(&interpreter_lock);
}

static void finalize_interpreter(void) {
    pthread_mutex_lock(&interpreter_lock);
    int running = interpreter_phase == RUNNING && getpid() == interpreter_process;
    if (running) {
        interpreter_phase = FINALIZE;
        pthread_cond_broadcast(&interpreter_changed);
    }
    pthread_mutex_unlock(&interpreter_lock);
    if (!running) return;
    wait_for_phase(FINALIZED_NOW);
    pthread_join(interpreter_thread, NULL);
}

/* The interpreter's thread: start it as pythonfmu would, without installing signal handlers
 * (the host keeps its own), publish the count, finalize when asked. */
static void* interpreter_main(void* unused) {
    (void)unused;
    Py_SetProgramName(L"./PythonFMU");   /* pythonfmu's: Python found by PYTHONHOME, else its
                                          * own prefix */
    Py_InitializeEx(0);
    /* threading's main thread is the one that imports it: this one, as in any Python
     * process, so that finalizing here waits for no thread a host called an FMU from */
    PyObject* threading = PyImport_ImportModule("threading");
    if (threading) Py_DecRef(threading);
    else PyErr_Clear();
    own_count.finalize = finalize_interpreter;
    PyObject* capsule = PyCapsule_New(&own_count, SHARED_COUNT, NULL);
    if (!capsule || PySys_SetObject(SHARED_COUNT, capsule) != 0) PyErr_Clear();
    if (capsule) Py_DecRef(capsule);
    PyThreadState* state = PyEval_SaveThread();
    set_phase(RUNNING);
    wait_for_phase(FINALIZE);
    PyEval_RestoreThread(state);
    Py_FinalizeEx();
    set_phase(FINALIZED_NOW);
    return NULL;
}

static int start_interpreter(void) {
    interpreter_process = getpid();
    if (pthread_create(&interpreter_thread, NULL, interpreter_main, NULL) != 0) return 0;
    wait_for_phase(RUNNING);
    shared = &own_count;
    return 1;
}

/* The count of the shim that started the interpreter, if one did (Python running). */
static SharedCount* find_shared_count(void) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* capsule = PySys_GetObject(SHARED_COUNT);   /* borrowed */
    SharedCount* found = capsule ? PyCapsule_GetPointer(capsule, SHARED_COUNT) : NULL;
    PyErr_Clear();
    PyGILState_Release(gil);
    return found;
}

/* Each thread that calls an FMU and has no Python thread state keeps one: without it,
 * every PyGILState_Ensure/Release (pythonfmu's, the direct access's) creates and deletes a
 * state, which made OMSimulator's command line (FMUs called from a worker thread) 3.7x slower
 * than its Python API on yang2020, and libcosim's worker threads in a Python host (libcosimpy)
 * 2x slower. The state is kept by leaving the thread's GIL-state count at one; the
 * interpreter's finalization deletes it (a Python host's own threads have theirs already).
 * A kept state outlives its thread if the thread ends first (libcosim starts threads per
 * execution): measured, 30 libcosim executions of yang2020 in one process kept 1.4 MiB more
 * than without, against the 90 MiB libcosim and pythonfmu keep for them anyway. */
static __thread int thread_state_kept;

static void keep_thread_state(void) {
    if (thread_state_kept) return;
    if (!shared && PyGILState_GetThisThreadState()) {   /* a Python host's own thread */
        thread_state_kept = 1;
        return;
    }
    PyGILState_Ensure();
    PyEval_SaveThread();
    thread_state_kept = 1;
}

static void count_instance(long change) {
    pthread_mutex_lock(&lock);
    held_here += change;
    pthread_mutex_unlock(&lock);
    if (!shared) return;
    pthread_mutex_lock(&shared->lock);
    shared->held += change;
    int last = shared->held == 0 && shared->exiting;
    pthread_mutex_unlock(&shared->lock);
    if (last) shared->finalize();
}

/* ---------------------------------------------------------------- loading pythonfmu */
static void* library;                    /* pythonfmu's */
static int owns_interpreter;             /* this shim started the interpreter (a C host) */

/* Run at exit, or when the host unloads this library (a handler registered by a shared
 * library also runs at its dlclose): release pythonfmu's state before its static destructors
 * and unload hook do (twice); pooled instances are freed while their Python is alive. The
 * instances the host still holds keep pythonfmu loaded and the interpreter running: a host
 * may free them in its own exit handlers, which run after this one. */
static void release_pythonfmu(void) {
    int alive = python_alive();
    pthread_mutex_lock(&lock);
    for (size_t i = 0; i < pooled; i++) discard(pool[i]);
    pooled = 0;
    released = 1;
    int held = held_here > 0;
    pthread_mutex_unlock(&lock);
    if (pythonfmu.finalize) pythonfmu.finalize();   /* pythonfmu never owns the interpreter */
    if (owns_interpreter) {
        pthread_mutex_lock(&own_count.lock);
        own_count.exiting = 1;
        int last = own_count.held == 0;
        pthread_mutex_unlock(&own_count.lock);
        if (last) finalize_interpreter();
    } else if (alive && !held) {   /* unloaded by a Python host: unload pythonfmu too */
        dlclose(library);
        library = NULL;
        load_state = 0;
        released = 0;
    }
}

static int load_pythonfmu(void) {
    pthread_mutex_lock(&lock);
    if (load_state != 0) {
        pthread_mutex_unlock(&lock);
        return load_state > 0;
    }
    Dl_info self;
    char path[4096];
    load_state = -1;
    if (!dladdr((void*)&load_pythonfmu, &self) || !self.dli_fname) {
        snprintf(load_error, sizeof load_error, "cannot find the FMU's own library file");
        goto done;
    }
    const char* slash = strrchr(self.dli_fname, '/');
    int folder = slash ? (int)(slash - self.dli_fname) + 1 : 0;
    snprintf(path, sizeof path, "%.*s%s", folder, self.dli_fname, PYTHONFMU_LIBRARY);
    /* In a host without a running Python, this shim starts the interpreter; it cannot be
     * started again (numpy), so pythonfmu and this library stay loaded until exit. */
    if (saw_python && !python_alive()) {
        snprintf(load_error, sizeof load_error, "%s", FINALIZED);
        goto done;
    }
    owns_interpreter = !python_alive();
    if (owns_interpreter && !start_interpreter()) {
        snprintf(load_error, sizeof load_error, "cannot start a thread for the interpreter");
        goto done;
    }
    if (!owns_interpreter) shared = find_shared_count();
    saw_python = 1;
    library = dlopen(path, RTLD_NOW | RTLD_LOCAL | (owns_interpreter ? RTLD_NODELETE : 0));
    if (!library) {
        snprintf(load_error, sizeof load_error, "cannot load pythonfmu's library: %s",
                 dlerror());
        goto done;
    }
#define RESOLVE(name) \
    if (!(pythonfmu.name = (__typeof__(name)*)dlsym(library, #name))) { \
        snprintf(load_error, sizeof load_error, "%s lacks %s", path, #name); \
        goto done; \
    }
    FORWARDED(RESOLVE)
#undef RESOLVE
    pythonfmu.finalize = (void (*)(void))dlsym(library, "finalizePythonInterpreter");
    if (owns_interpreter) dlopen(self.dli_fname, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
    atexit(release_pythonfmu);   /* after pythonfmu's static constructors: runs before */
    load_state = 1;
done:
    pthread_mutex_unlock(&lock);
    return load_state > 0;
}

EXPORT void finalizePythonInterpreter(void) {
    if (load_state > 0 && pythonfmu.finalize) pythonfmu.finalize();
}

/* ---------------------------------------------------------------- resource URIs */
static int hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    c = (char)tolower((unsigned char)c);
    return c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}

/* The local folder a resource location names (file:/p, file:///p, file://localhost/p, or a
 * plain absolute path), percent-decoded; NULL with the reason in `error`. */
static char* resource_folder(fmi2String location, char* error, size_t size) {
    if (!location || !*location) {
        snprintf(error, size, "no resource location given");
        return NULL;
    }
    const char* path = location;
    if (strncasecmp(location, "file:", 5) == 0) {
        path = location + 5;
        if (strncmp(path, "//", 2) == 0) {
            const char* authority = path + 2;
            const char* end = strchr(authority, '/');
            size_t length = end ? (size_t)(end - authority) : strlen(authority);
            if (!end || (length && !(length == 9 && strncasecmp(authority, "localhost", 9) == 0))) {
                snprintf(error, size, "resource location '%s' names no local folder "
                         "(expected file:/path, file:///path or file://localhost/path)", location);
                return NULL;
            }
            path = end;
        }
    }
    if (path[0] != '/') {
        snprintf(error, size, "resource location '%s' is not an absolute file URI "
                 "(expected file:/path, file:///path or file://localhost/path)", location);
        return NULL;
    }
    char* folder = malloc(strlen(path) + 1);
    if (!folder) {
        snprintf(error, size, "out of memory");
        return NULL;
    }
    char* out = folder;
    for (const char* p = path; *p; p++) {
        if (*p != '%') {
            *out++ = *p;
            continue;
        }
        int high = p[1] ? hex_digit(p[1]) : -1, low = high >= 0 && p[2] ? hex_digit(p[2]) : -1;
        if (high < 0 || low < 0 || (high == 0 && low == 0)) {
            snprintf(error, size, "resource location '%s' has an invalid percent-escape",
                     location);
            free(folder);
            return NULL;
        }
        *out++ = (char)(high * 16 + low);
        p += 2;
    }
    *out = '\0';
    if (strstr(folder, "%20")) {   /* pythonfmu would read it as a space */
        snprintf(error, size, "resource folder '%s' contains '%%20', which pythonfmu misreads",
                 folder);
        free(folder);
        return NULL;
    }
    return folder;
}

/* ---------------------------------------------------------------- direct access */
/* pythonfmu turns each fmi2Get/Set into a Python call of the slave's get_<type>/set_<type>
 * with a list of value references built anew, and each call also makes four strings to drain
 * the slave's log queue: ~13,000 instructions per call, more than the values cost. While an
 * instance steps (from fmi2ExitInitializationMode to fmi2EnterInitializationMode, fmi2Reset
 * or fmi2Terminate), the shim reads the inputs and outputs (the core's attributes) and the
 * parameters (the parameter set's), strings included, and sets the inputs itself (what
 * altfusion.fmi.slave's accessors do for them, with the conversions pythonfmu makes), and
 * calls the slave's do_step, passing its log messages on as pythonfmu does. Anything else
 * goes to pythonfmu as before: a parameter or output set, a value that does not convert
 * (pythonfmu then logs why), Initialization Mode, a slave that is not a CoreSlave.
 *
 * The shim learns the slave object when pythonfmu makes it (fmi2Instantiate, fmi2Reset): it
 * leaves the calling thread a slot (None, keyed by threading.get_ident()) in a dict in `sys`
 * named SLAVE_SLOTS, which CoreSlave.__init__ fills with itself; its _native_names() lists
 * the attribute names by value reference. */
#define SLAVE_SLOTS "_altfusion_fmi2_shim_slaves_v1"

static PyObject* none;             /* None */
static PyObject* core_name;        /* "core", interned */
static PyObject* parameters_name;  /* "_params", interned */
static PyObject* do_step_name;   /* "do_step", interned */

/* Under the GIL: the objects the shim names, made once (0 if one cannot be). */
static int names_made(void) {
    if (!none) none = Py_BuildValue("");
    if (!core_name) core_name = PyUnicode_InternFromString("core");
    if (!parameters_name) parameters_name = PyUnicode_InternFromString("_params");
    if (!do_step_name) do_step_name = PyUnicode_InternFromString("do_step");
    return none && core_name && parameters_name && do_step_name;
}

/* Under the GIL: release each of `count` references that is not NULL. */
static void release(PyObject* const objects[], size_t count) {
    for (size_t i = 0; i < count; i++)
        if (objects[i]) Py_DecRef(objects[i]);
}

/* Under the GIL: a slot for the slave the calling thread is about to make; its key, or NULL. */
static PyObject* open_slot(void) {
    PyObject* slots = PySys_GetObject(SLAVE_SLOTS);   /* borrowed */
    if (!slots) {
        PyObject* made = PyDict_New();
        if (made && PySys_SetObject(SLAVE_SLOTS, made) == 0) slots = made;
        if (made) Py_DecRef(made);                     /* sys holds it */
    }
    PyObject* key = PyLong_FromUnsignedLong((unsigned long)pthread_self());
    if (!names_made() || !slots || !key || PyDict_SetItem(slots, key, none) != 0) {
        if (key) Py_DecRef(key);
        key = NULL;
    }
    PyErr_Clear();
    return key;
}

/* Under the GIL: the slave left in the slot `key` (a new reference, or NULL); the slot goes. */
static PyObject* close_slot(PyObject* key) {
    if (!key) return NULL;
    PyObject* slots = PySys_GetObject(SLAVE_SLOTS);
    PyObject* found = slots ? PyDict_GetItem(slots, key) : NULL;   /* borrowed */
    PyObject* slave = found && found != none ? found : NULL;
    if (slave) Py_IncRef(slave);
    if (found) PyDict_DelItem(slots, key);
    Py_DecRef(key);
    PyErr_Clear();
    return slave;
}

static void drop_slave(Instance* inst) {
    inst->direct = 0;
    for (int way = READ; way <= WRITE; way++)
        for (int kind = 0; kind < KINDS; kind++) {
            free(inst->names[way][kind]);
            free(inst->owners[way][kind]);
            inst->names[way][kind] = NULL;
            inst->owners[way][kind] = NULL;
            inst->n_names[way][kind] = 0;
        }
    PyObject* held[] = {inst->slave, inst->tables, inst->log_queue, inst->strings};
    inst->slave = inst->tables = inst->log_queue = inst->strings = NULL;
    if (!held[0] || !python_alive()) return;   /* the interpreter took them with it */
    PyGILState_STATE gil = PyGILState_Ensure();
    release(held, sizeof held / sizeof *held);
    PyGILState_Release(gil);
}

/* Under the GIL: `table` (by value reference, None or (owner, attribute name)) as arrays. */
static int name_array(PyObject* table, PyObject*** names, unsigned char** owners,
                      size_t* count) {
    long n = table ? PyTuple_Size(table) : -1;
    if (n < 0) return 0;
    *names = calloc(n ? (size_t)n : 1, sizeof **names);
    *owners = calloc(n ? (size_t)n : 1, sizeof **owners);
    if (!*names || !*owners) return 0;
    *count = (size_t)n;
    int ok = 1;
    for (long vr = 0; ok && vr < n; vr++) {
        PyObject* entry = PyTuple_GetItem(table, vr);   /* borrowed from `tables` */
        if (entry == none) continue;
        PyObject* owner = entry && PyTuple_Size(entry) == 2 ? PyTuple_GetItem(entry, 0) : NULL;
        PyObject* name = owner ? PyTuple_GetItem(entry, 1) : NULL;
        long code = owner ? PyLong_AsLong(owner) : -1;
        ok = name && PyUnicode_GetLength(name) > 0 && code >= 0 && code < OWNERS;
        (*names)[vr] = name;
        (*owners)[vr] = (unsigned char)code;
    }
    return ok;
}

/* Under the GIL: take `slave` (a new reference) for direct access if it offers it. */
static void adopt_slave(Instance* inst, PyObject* slave) {
    if (!slave) return;
    inst->slave = slave;
    PyObject* method = PyObject_GetAttrString(slave, "_native_names");
    inst->tables = method ? PyObject_CallFunctionObjArgs(method, NULL) : NULL;
    if (method) Py_DecRef(method);
    method = PyObject_GetAttrString(slave, "_get_log_queue");
    inst->log_queue = method ? PyObject_CallFunctionObjArgs(method, NULL) : NULL;
    if (method) Py_DecRef(method);
    int ready = names_made() && inst->tables && inst->log_queue
        && PyTuple_Size(inst->tables) == 2 && PyList_Size(inst->log_queue) >= 0;
    for (int way = READ; ready && way <= WRITE; way++) {
        PyObject* by_kind = PyTuple_GetItem(inst->tables, way);
        ready = by_kind && PyTuple_Size(by_kind) == KINDS;
        for (int kind = 0; ready && kind < KINDS; kind++)
            ready = name_array(PyTuple_GetItem(by_kind, kind), &inst->names[way][kind],
                               &inst->owners[way][kind], &inst->n_names[way][kind]);
    }
    PyErr_Clear();
    if (!ready) drop_slave(inst);   /* not one of ours: pythonfmu serves it */
}

/* Call pythonfmu's `make` (fmi2Instantiate's or fmi2Reset's), which makes a new slave object,
 * and take that object for direct access. */
#define MAKING_SLAVE(inst, make) do { \
        PyGILState_STATE gil_ = PyGILState_Ensure(); \
        PyObject* slot_ = open_slot(); \
        PyGILState_Release(gil_); \
        make; \
        gil_ = PyGILState_Ensure(); \
        PyObject* slave_ = close_slot(slot_); \
        if ((inst)->inner) adopt_slave((inst), slave_); \
        else if (slave_) Py_DecRef(slave_); \
        PyGILState_Release(gil_); \
    } while (0)

/* The attribute of value reference `vr` of type `kind` that may be read or written
 * (`way`) directly, or NULL. */
static PyObject* direct_name(const Instance* inst, int way, int kind, fmi2ValueReference vr) {
    return vr < inst->n_names[way][kind] ? inst->names[way][kind][vr] : NULL;
}

/* Under the GIL: the object whose attribute value reference `vr` is (a new reference, or
 * NULL): the core, its parameters or the slave, each looked up once per call (`held`). */
static PyObject* owner(const Instance* inst, int way, int kind, fmi2ValueReference vr,
                       PyObject* held[OWNERS]) {
    int code = inst->owners[way][kind][vr];
    if (!held[code])
        held[code] = code == CORE ? PyObject_GetAttr(inst->slave, core_name)
            : code == PARAMETERS ? PyObject_GetAttr(inst->slave, parameters_name)
            : (Py_IncRef(inst->slave), inst->slave);
    return held[code];
}

/* Read `n` values of type `kind` into `values` (strings: kept until the next direct
 * fmi2GetString, as pythonfmu keeps them); 0 (nothing to report) if any cannot be read
 * directly: pythonfmu reads them all then. */
static int get_direct(Instance* inst, int kind, const fmi2ValueReference vr[], size_t n,
                      void* values) {
    if (!inst->direct) return 0;
    for (size_t i = 0; i < n; i++)
        if (!direct_name(inst, READ, kind, vr[i])) return 0;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* held[OWNERS] = {NULL, NULL, NULL};
    PyObject* strings = kind == STRING ? PyList_New((long)n) : NULL;
    size_t i = 0;
    for (; (kind != STRING || strings) && i < n; i++) {
        PyObject* object = owner(inst, READ, kind, vr[i], held);
        PyObject* value = object ? PyObject_GetAttr(object, direct_name(inst, READ, kind, vr[i]))
            : NULL;
        if (!value) break;
        int ok;
        if (kind == REAL) {             /* float(value), as the adapter converts */
            double x = PyFloat_AsDouble(value);
            ok = x != -1.0 || !PyErr_Occurred();
            ((fmi2Real*)values)[i] = x;
        } else if (kind == INTEGER) {   /* int(value) of an int; pythonfmu's cast to int */
            long x = PyLong_AsLong(value);
            ok = x != -1 || !PyErr_Occurred();
            ((fmi2Integer*)values)[i] = (fmi2Integer)x;
        } else if (kind == BOOLEAN) {   /* bool(value) */
            int x = PyObject_IsTrue(value);
            ok = x >= 0;
            ((fmi2Boolean*)values)[i] = x;
        } else {                        /* a str, UTF-8 (pythonfmu's encoding) */
            const char* text = PyUnicode_AsUTF8(value);
            ok = text != NULL;
            ((fmi2String*)values)[i] = text;
            if (ok) {
                Py_IncRef(value);
                PyList_SetItem(strings, (long)i, value);   /* steals; keeps `text` alive */
            }
        }
        Py_DecRef(value);
        if (!ok) break;
    }
    release(held, OWNERS);
    int done = i == n;
    if (kind == STRING && done) {
        if (inst->strings) Py_DecRef(inst->strings);
        inst->strings = strings;
    } else if (strings) {
        Py_DecRef(strings);
    }
    PyErr_Clear();
    PyGILState_Release(gil);
    return done;
}

/* Set `n` inputs of type `kind` to the Python objects pythonfmu would make of `values`; 0 if
 * any is not an input read directly (pythonfmu sets them all then). */
static int set_direct(Instance* inst, int kind, const fmi2ValueReference vr[], size_t n,
                      const void* values) {
    if (!inst->direct) return 0;
    for (size_t i = 0; i < n; i++)
        if (!direct_name(inst, WRITE, kind, vr[i])) return 0;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* held[OWNERS] = {NULL, NULL, NULL};
    size_t i = 0;
    for (; i < n; i++) {
        PyObject* object = owner(inst, WRITE, kind, vr[i], held);
        PyObject* value = kind == REAL ? PyFloat_FromDouble(((const fmi2Real*)values)[i])
            : kind == INTEGER ? PyLong_FromLong(((const fmi2Integer*)values)[i])
            : PyBool_FromLong(((const fmi2Boolean*)values)[i]);
        int ok = object && value
            && PyObject_SetAttr(object, direct_name(inst, WRITE, kind, vr[i]), value) == 0;
        if (value) Py_DecRef(value);
        if (!ok) break;
    }
    release(held, OWNERS);
    PyErr_Clear();
    PyGILState_Release(gil);
    return i == n;
}

/* Under the GIL: the slave's log messages to the host, as pythonfmu passes them (each message
 * through its logger, as a format: the adapter escapes '%'), then the queue emptied. */
static void pass_messages(Instance* inst) {
    long n = PyList_Size(inst->log_queue);
    for (long i = 0; i < n; i++) {
        PyObject* message = PyList_GetItem(inst->log_queue, i);   /* borrowed */
        PyObject* status = message ? PyObject_GetAttrString(message, "status") : NULL;
        PyObject* category = message ? PyObject_GetAttrString(message, "category") : NULL;
        PyObject* text = message ? PyObject_GetAttrString(message, "msg") : NULL;
        long level = status ? PyLong_AsLong(status) : fmi2Error;
        const char* category_text = category ? PyUnicode_AsUTF8(category) : NULL;
        const char* message_text = text ? PyUnicode_AsUTF8(text) : NULL;
        PyErr_Clear();
        if (level < fmi2OK || level > fmi2Pending) level = fmi2Error;
        shim_logger(inst, inst->name, (fmi2Status)level, category_text,
                    message_text ? message_text : "(a log message that is not text)");
        if (status) Py_DecRef(status);
        if (category) Py_DecRef(category);
        if (text) Py_DecRef(text);
    }
    if (n > 0) PyList_SetSlice(inst->log_queue, 0, n, NULL);
    PyErr_Clear();
}

/* The slave's do_step(t, h), as pythonfmu's fmi2DoStep calls it: fmi2OK if it returns true,
 * fmi2Discard if false, fmi2Fatal with the exception if one escapes. */
static fmi2Status do_step_direct(Instance* inst, fmi2Real t, fmi2Real h) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* start = PyFloat_FromDouble(t);
    PyObject* step = PyFloat_FromDouble(h);
    PyObject* result = start && step
        ? PyObject_CallMethodObjArgs(inst->slave, do_step_name, start, step, NULL) : NULL;
    int ok = result ? PyObject_IsTrue(result) : -1;
    char reason[1024] = "";
    if (ok < 0) {
        PyObject *type = NULL, *value = NULL, *traceback = NULL;
        PyErr_Fetch(&type, &value, &traceback);
        PyObject* text = value ? PyObject_Str(value) : NULL;
        const char* utf8 = text ? PyUnicode_AsUTF8(text) : NULL;
        snprintf(reason, sizeof reason, "%s", utf8 ? utf8 : "an exception without a message");
        PyObject* held[] = {text, type, value, traceback};
        release(held, sizeof held / sizeof *held);
        PyErr_Clear();
    }
    PyObject* held[] = {result, start, step};
    release(held, sizeof held / sizeof *held);
    pass_messages(inst);
    PyGILState_Release(gil);
    if (ok < 0) {
        log_own(inst, fmi2Fatal, "fmi2DoStep: the slave's do_step raised: %s", reason);
        return fmi2Fatal;
    }
    return ok ? fmi2OK : fmi2Discard;
}

/* ---------------------------------------------------------------- life cycle */
/* Whether `guid` is the GUID of the slave pythonfmu made for `inst` (its `guid` attribute);
 * if not, the reason in `error`. A slave not taken for direct access (not a CoreSlave) is not
 * checked. */
static int guid_matches(const Instance* inst, fmi2String guid, char* error, size_t size) {
    if (!inst->slave) return 1;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* own = PyObject_GetAttrString(inst->slave, "guid");
    const char* text = own ? PyUnicode_AsUTF8(own) : NULL;
    int same = !text || (guid && strcmp(guid, text) == 0);
    if (!same)
        snprintf(error, size, "GUID '%s' is not this FMU's ('%s'): the host read the "
                 "modelDescription.xml of another build, whose value references may name "
                 "other variables; import this FMU again", guid ? guid : "(null)", text);
    if (own) Py_DecRef(own);
    PyErr_Clear();
    PyGILState_Release(gil);
    return same;
}

static Instance* take_pooled(fmi2String guid, const char* resources, fmi2Type type) {
    Instance* found = NULL;
    pthread_mutex_lock(&lock);
    for (size_t i = 0; i < pooled; i++) {
        Instance* candidate = pool[i];
        if (candidate->type == type && strcmp(candidate->guid, guid ? guid : "") == 0
                && strcmp(candidate->resources, resources) == 0) {
            found = candidate;
            pool[i] = pool[--pooled];
            break;
        }
    }
    pthread_mutex_unlock(&lock);
    return found;
}

static int put_pooled(Instance* inst) {
    int kept = 0;
    pthread_mutex_lock(&lock);
    if (pooled < POOL_SIZE) {
        pool[pooled++] = inst;
        kept = 1;
    }
    pthread_mutex_unlock(&lock);
    return kept;
}

EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                                     fmi2String location,
                                     const fmi2CallbackFunctions* functions,
                                     fmi2Boolean visible, fmi2Boolean logging_on) {
    if (!functions) return NULL;
    char error[1500];
    Instance probe = {.host = *functions, .name = (char*)name};   /* to report failures */
    if (!load_pythonfmu()) {
        log_own(&probe, fmi2Fatal, "fmi2Instantiate: %s", load_error);
        return NULL;
    }
    if (!python_alive()) {
        log_own(&probe, fmi2Error, "fmi2Instantiate: %s", FINALIZED);
        return NULL;
    }
    keep_thread_state();
    char* resources = resource_folder(location, error, sizeof error);
    if (!resources) {
        log_own(&probe, fmi2Error, "fmi2Instantiate: %s", error);
        return NULL;
    }
    Instance* inst = take_pooled(guid, resources, type);
    if (inst) {
        free(resources);
        free(inst->name);
        inst->name = copy_string(name);
        inst->host = *functions;
        inst->logging = logging_on;
        count_instance(1);
        return inst;
    }
    inst = calloc(1, sizeof *inst);
    char* uri = malloc(strlen(resources) + 8);
    if (!inst || !uri) {
        free(inst);
        free(uri);
        free(resources);
        log_own(&probe, fmi2Fatal, "fmi2Instantiate: out of memory");
        return NULL;
    }
    sprintf(uri, "file://%s", resources);
    inst->host = *functions;
    inst->own = (fmi2CallbackFunctions){shim_logger, calloc, free, NULL, inst};
    inst->name = copy_string(name);
    inst->guid = copy_string(guid ? guid : "");
    inst->resources = resources;
    inst->type = type;
    inst->logging = logging_on;
    inst->last_successful = NAN;
    MAKING_SLAVE(inst, inst->inner = pythonfmu.fmi2Instantiate(name, type, guid, uri, &inst->own,
                                                               visible, fmi2True));
    free(uri);
    if (!inst->inner) {
        destroy(inst);
        return NULL;
    }
    if (!guid_matches(inst, guid, error, sizeof error)) {
        log_own(&probe, fmi2Error, "fmi2Instantiate: %s", error);
        discard(inst);
        return NULL;
    }
    count_instance(1);
    return inst;
}

/* pythonfmu's fmi2Reset, which makes a new slave object: direct access to that one. */
static fmi2Status reset(Instance* inst) {
    fmi2Status status;
    drop_slave(inst);
    inst->last_successful = NAN;
    MAKING_SLAVE(inst, status = pythonfmu.fmi2Reset(inst->inner));
    return status;
}

/* Keep a healthy instance for reuse (1); never once release_pythonfmu ran (0). */
static int pool_instance(Instance* inst) {
    inst->worst = fmi2OK;
    if (released || inst->broken || reset(inst) != fmi2OK || inst->worst > fmi2Warning)
        return 0;
    inst->host.logger = NULL;   /* the host's callbacks end here */
    clear_categories(inst);
    return put_pooled(inst);
}

EXPORT void fmi2FreeInstance(fmi2Component c) {
    Instance* inst = c;
    if (!inst) return;
    if (!python_alive() || !pool_instance(inst)) discard(inst);
    count_instance(-1);   /* last: it may finalize the interpreter */
}

EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t count,
                                      const fmi2String categories[]) {
    Instance* inst = c;
    if (!inst) return fmi2Error;
    clear_categories(inst);
    inst->logging = on;
    if (count > MAX_CATEGORIES) {
        inst->worst = fmi2OK;
        log_own(inst, fmi2Warning, "fmi2SetDebugLogging: more than %d categories, logging all",
                MAX_CATEGORIES);
        return fmi2Warning;
    }
    for (size_t i = 0; on && categories && i < count; i++)
        if (categories[i]) inst->categories[inst->n_categories++] = strdup(categories[i]);
    return fmi2OK;
}

/* ---------------------------------------------------------------- forwarding */
/* A call once the interpreter has been finalized: nothing to do for fmi2Terminate,
 * fmi2Error for anything else (fmi2FreeInstance and fmi2FreeFMUstate are answered where they
 * are defined). */
static fmi2Status after_finalization(Instance* inst, const char* function) {
    if (strcmp(function, "fmi2Terminate") == 0) return fmi2OK;
    log_own(inst, fmi2Error, "%s: %s", function, FINALIZED);
    return fmi2Error;
}

#define ARGS(...) __VA_ARGS__
#define BEGIN(c) \
    Instance* inst = (c); \
    if (!inst) return fmi2Error; \
    inst->worst = fmi2OK; \
    if (!python_alive()) return after_finalization(inst, __func__); \
    keep_thread_state();
#define END(status) \
    fmi2Status result = (status); /* before reading inst->worst, which the call updates */ \
    if (inst->worst > fmi2Warning) result = worse(result, inst->worst); \
    if (result == fmi2Fatal) inst->broken = 1; \
    return result;
#define FORWARD(name, params, args) \
    EXPORT fmi2Status name(fmi2Component c, ARGS params) { \
        BEGIN(c) \
        END(pythonfmu.name(inst->inner, ARGS args)) \
    }
#define FORWARD0(name) \
    EXPORT fmi2Status name(fmi2Component c) { \
        BEGIN(c) \
        END(pythonfmu.name(inst->inner)) \
    }

FORWARD(fmi2SetupExperiment, (fmi2Boolean a, fmi2Real b, fmi2Real d, fmi2Boolean e, fmi2Real f),
        (a, b, d, e, f))
/* Direct access (see there) from the end of Initialization Mode to its next start, a reset
 * or fmi2Terminate. */
#define ENDS_DIRECT_ACCESS(name) \
    EXPORT fmi2Status name(fmi2Component c) { \
        BEGIN(c) \
        inst->direct = 0; \
        END(pythonfmu.name(inst->inner)) \
    }
ENDS_DIRECT_ACCESS(fmi2EnterInitializationMode)
ENDS_DIRECT_ACCESS(fmi2Terminate)

EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    BEGIN(c)
    fmi2Status status = pythonfmu.fmi2ExitInitializationMode(inst->inner);
    inst->direct = inst->slave && status <= fmi2Warning && inst->worst <= fmi2Warning;
    END(status)
}

EXPORT fmi2Status fmi2Reset(fmi2Component c) {
    BEGIN(c)
    END(reset(inst))
}

#define DIRECT_OR_FORWARD(name, access, kind, constness, type) \
    EXPORT fmi2Status name(fmi2Component c, const fmi2ValueReference v[], size_t n, \
                           constness type x[]) { \
        BEGIN(c) \
        if (access(inst, kind, v, n, x)) return fmi2OK; \
        END(pythonfmu.name(inst->inner, v, n, x)) \
    }
DIRECT_OR_FORWARD(fmi2GetReal, get_direct, REAL, , fmi2Real)
DIRECT_OR_FORWARD(fmi2GetInteger, get_direct, INTEGER, , fmi2Integer)
DIRECT_OR_FORWARD(fmi2GetBoolean, get_direct, BOOLEAN, , fmi2Boolean)
DIRECT_OR_FORWARD(fmi2SetReal, set_direct, REAL, const, fmi2Real)
DIRECT_OR_FORWARD(fmi2SetInteger, set_direct, INTEGER, const, fmi2Integer)
DIRECT_OR_FORWARD(fmi2SetBoolean, set_direct, BOOLEAN, const, fmi2Boolean)
FORWARD0(fmi2CancelStep)
DIRECT_OR_FORWARD(fmi2GetString, get_direct, STRING, , fmi2String)
FORWARD(fmi2SetString, (const fmi2ValueReference v[], size_t n, const fmi2String x[]), (v, n, x))
FORWARD(fmi2GetFMUstate, (fmi2FMUstate* s), (s))
FORWARD(fmi2SetFMUstate, (fmi2FMUstate s), (s))
FORWARD(fmi2SerializedFMUstateSize, (fmi2FMUstate s, size_t* n), (s, n))
FORWARD(fmi2SerializeFMUstate, (fmi2FMUstate s, fmi2Byte b[], size_t n), (s, b, n))
FORWARD(fmi2GetDirectionalDerivative,
        (const fmi2ValueReference u[], size_t nu, const fmi2ValueReference z[], size_t nz,
         const fmi2Real du[], fmi2Real dz[]), (u, nu, z, nz, du, dz))
FORWARD(fmi2SetRealInputDerivatives,
        (const fmi2ValueReference v[], size_t n, const fmi2Integer o[], const fmi2Real x[]),
        (v, n, o, x))
FORWARD(fmi2GetRealOutputDerivatives,
        (const fmi2ValueReference v[], size_t n, const fmi2Integer o[], fmi2Real x[]),
        (v, n, o, x))
FORWARD(fmi2GetStatus, (const fmi2StatusKind k, fmi2Status* x), (k, x))

/* The last successful time is the shim's to answer: direct steps pass pythonfmu by. */
EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean flag) {
    BEGIN(c)
    fmi2Status status = inst->direct ? do_step_direct(inst, t, h)
        : pythonfmu.fmi2DoStep(inst->inner, t, h, flag);
    if (status == fmi2OK || status == fmi2Discard)
        inst->last_successful = status == fmi2OK ? t + h : t;
    END(status)
}

EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* x) {
    BEGIN(c)
    if (kind == fmi2LastSuccessfulTime && x) {
        *x = inst->last_successful;
        return fmi2OK;
    }
    END(pythonfmu.fmi2GetRealStatus(inst->inner, kind, x))
}
FORWARD(fmi2GetIntegerStatus, (const fmi2StatusKind k, fmi2Integer* x), (k, x))
FORWARD(fmi2GetBooleanStatus, (const fmi2StatusKind k, fmi2Boolean* x), (k, x))
FORWARD(fmi2GetStringStatus, (const fmi2StatusKind k, fmi2String* x), (k, x))

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
    if (c && state && !python_alive()) {   /* the state went with the interpreter */
        *state = NULL;
        return fmi2OK;
    }
    BEGIN(c)
    END(pythonfmu.fmi2FreeFMUstate(inst->inner, state))
}

/* ---------------------------------------------------------------- refused states */
/* The reason a deserialized state was refused (its Python object's `reason`, a str; see
 * altfusion.fmi.state.RefusedState), copied into `reason`; 0 if the state was accepted. */
static int refusal(fmi2FMUstate state, char* reason, size_t size) {
    if (!state) return 0;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* value = PyObject_GetAttrString((PyObject*)state, "reason");
    const char* text = value ? PyUnicode_AsUTF8(value) : NULL;
    if (text) snprintf(reason, size, "%s", text);
    PyErr_Clear();
    if (value) Py_DecRef(value);
    PyGILState_Release(gil);
    return text != NULL;
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                          fmi2FMUstate* state) {
    BEGIN(c)
    fmi2Status status = pythonfmu.fmi2DeSerializeFMUstate(inst->inner, bytes, size, state);
    char reason[1500];
    if (status <= fmi2Warning && state && refusal(*state, reason, sizeof reason)) {
        pythonfmu.fmi2FreeFMUstate(inst->inner, state);
        *state = NULL;
        log_own(inst, fmi2Error, "fmi2DeSerializeFMUstate refused the state: %s", reason);
    }
    END(status)
}

EXPORT const char* fmi2GetTypesPlatform(void) {
    return "default";
}

EXPORT const char* fmi2GetVersion(void) {
    return "2.0";
}
