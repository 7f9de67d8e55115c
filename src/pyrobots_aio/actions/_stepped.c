/*
 * pyrobots_aio.actions._stepped: the pause trampoline, in C.
 *
 * The same object as `pyrobots_aio.actions._pause.PyStepped` (read its
 * docstring for the rules), built where a C compiler is at hand. An action's
 * task awaits it in the body's place once per action, and each resumption of
 * the body passes through it; in C the common case (nothing paused) costs one
 * attribute read and a `PyIter_Send` into the body, and the body's return
 * value comes back without an exception (`am_send`).
 *
 * Stepped(hold, executive, handle, coro):
 *   hold(handle) -> future | None: the thaw future while `handle` is frozen
 *   (marked as blocking, as `yield from future` marks it), else None. Called
 *   only when `executive.paused` is true, or to finish a thaw.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

typedef struct {
    PyObject_HEAD
    PyObject *hold;      /* the gate: hold(handle) -> thaw future or None */
    PyObject *executive; /* read: .paused (0 while nothing is frozen) */
    PyObject *handle;
    PyObject *coro;      /* the body */
    PyObject *held;      /* the value the body gets when it thaws, or NULL */
    int thawing;         /* the task waits for the thaw future */
} Stepped;

static PyObject *str_paused;
static PyObject *str_throw;
static PyObject *str_close;

static PyTypeObject Stepped_Type;

static PyObject *
stepped_make(PyTypeObject *type, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    Py_ssize_t nargs = PyVectorcall_NARGS(nargsf);
    if (kwnames != NULL && PyTuple_GET_SIZE(kwnames) != 0) {
        PyErr_SetString(PyExc_TypeError, "Stepped() takes no keyword arguments");
        return NULL;
    }
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError,
                     "Stepped(hold, executive, handle, coro) takes 4 arguments, not %zd", nargs);
        return NULL;
    }
    Stepped *self = PyObject_GC_New(Stepped, type);
    if (self == NULL) {
        return NULL;
    }
    self->hold = Py_NewRef(args[0]);
    self->executive = Py_NewRef(args[1]);
    self->handle = Py_NewRef(args[2]);
    self->coro = Py_NewRef(args[3]);
    self->held = NULL;
    self->thawing = 0;
    PyObject_GC_Track(self);
    return (PyObject *)self;
}

static PyObject *
stepped_vectorcall(PyObject *type, PyObject *const *args, size_t nargsf, PyObject *kwnames)
{
    return stepped_make((PyTypeObject *)type, args, nargsf, kwnames);
}

static PyObject *
stepped_new(PyTypeObject *type, PyObject *args, PyObject *kwargs)
{
    if (kwargs != NULL && PyDict_GET_SIZE(kwargs) != 0) {
        PyErr_SetString(PyExc_TypeError, "Stepped() takes no keyword arguments");
        return NULL;
    }
    return stepped_make(type, &PyTuple_GET_ITEM(args, 0), (size_t)PyTuple_GET_SIZE(args), NULL);
}

static int
stepped_traverse(Stepped *self, visitproc visit, void *arg)
{
    Py_VISIT(self->hold);
    Py_VISIT(self->executive);
    Py_VISIT(self->handle);
    Py_VISIT(self->coro);
    Py_VISIT(self->held);
    return 0;
}

static int
stepped_clear(Stepped *self)
{
    Py_CLEAR(self->hold);
    Py_CLEAR(self->executive);
    Py_CLEAR(self->handle);
    Py_CLEAR(self->coro);
    Py_CLEAR(self->held);
    return 0;
}

static void
stepped_dealloc(Stepped *self)
{
    PyObject_GC_UnTrack(self);
    stepped_clear(self);
    PyObject_GC_Del(self);
}

/* Forward one resumption to the body, or hold it while the action is frozen. */
static PySendResult
stepped_am_send(Stepped *self, PyObject *value, PyObject **result)
{
    PyObject *arg;
    if (self->thawing) { /* the thaw future is done: the kept value, once the action thaws */
        arg = self->held != NULL ? self->held : Py_NewRef(Py_None);
        self->held = NULL;
        self->thawing = 0;
    }
    else {
        arg = Py_NewRef(value);
    }
    PyObject *paused = PyObject_GetAttr(self->executive, str_paused);
    if (paused == NULL) {
        goto failed;
    }
    int some = PyObject_IsTrue(paused);
    Py_DECREF(paused);
    if (some < 0) {
        goto failed;
    }
    if (some) {
        PyObject *thaw = PyObject_CallOneArg(self->hold, self->handle);
        if (thaw == NULL) {
            goto failed;
        }
        if (thaw != Py_None) {
            self->held = arg;
            self->thawing = 1;
            *result = thaw;
            return PYGEN_NEXT;
        }
        Py_DECREF(thaw);
    }
    PySendResult status = PyIter_Send(self->coro, arg, result);
    Py_DECREF(arg);
    return status;
failed:
    Py_DECREF(arg);
    *result = NULL;
    return PYGEN_ERROR;
}

/* Raise StopIteration(result), as a generator returning result does; steals result. */
static PyObject *
stepped_returned(PyObject *result)
{
    /* StopIteration(value): a tuple or an exception as the value must not be unpacked */
    PyObject *stop = PyObject_CallOneArg(PyExc_StopIteration, result);
    Py_DECREF(result);
    if (stop != NULL) {
        PyErr_SetObject(PyExc_StopIteration, stop);
        Py_DECREF(stop);
    }
    return NULL;
}

static PyObject *
stepped_iternext(Stepped *self)
{
    PyObject *result;
    PySendResult status = stepped_am_send(self, Py_None, &result);
    if (status != PYGEN_RETURN) {
        return result; /* the next value, or NULL with the body's error set */
    }
    if (result == Py_None) { /* the common ending: no StopIteration instance to make */
        Py_DECREF(result);
        PyErr_SetNone(PyExc_StopIteration);
        return NULL;
    }
    return stepped_returned(result);
}

static PyObject *
stepped_send(Stepped *self, PyObject *value)
{
    PyObject *result;
    PySendResult status = stepped_am_send(self, value, &result);
    return status == PYGEN_RETURN ? stepped_returned(result) : result;
}

static void
stepped_forget(Stepped *self)
{
    self->thawing = 0;
    Py_CLEAR(self->held);
}

/* throw(exception), throw(type[, value[, traceback]]): into the body at once, frozen or not. */
static PyObject *
stepped_throw(Stepped *self, PyObject *const *args, Py_ssize_t nargs)
{
    if (nargs < 1 || nargs > 3) {
        PyErr_Format(PyExc_TypeError, "throw expected 1 to 3 arguments, got %zd", nargs);
        return NULL;
    }
    PyObject *kind = args[0];
    PyObject *value = nargs > 1 ? args[1] : Py_None;
    PyObject *traceback = nargs > 2 ? args[2] : Py_None;
    PyObject *error;
    if (PyExceptionInstance_Check(kind)) {
        error = Py_NewRef(kind);
    }
    else if (PyExceptionInstance_Check(value)) {
        error = Py_NewRef(value);
    }
    else if (value == Py_None) {
        error = PyObject_CallNoArgs(kind);
    }
    else {
        error = PyObject_CallOneArg(kind, value);
    }
    if (error == NULL) {
        return NULL;
    }
    if (!PyExceptionInstance_Check(error)) {
        PyErr_Format(PyExc_TypeError, "exceptions must derive from BaseException, not %R", error);
        Py_DECREF(error);
        return NULL;
    }
    if (traceback != Py_None && PyException_SetTraceback(error, traceback) < 0) {
        Py_DECREF(error);
        return NULL;
    }
    stepped_forget(self);
    PyObject *result = PyObject_CallMethodOneArg(self->coro, str_throw, error);
    Py_DECREF(error);
    return result;
}

static PyObject *
stepped_close(Stepped *self, PyObject *Py_UNUSED(ignored))
{
    stepped_forget(self);
    return PyObject_CallMethodNoArgs(self->coro, str_close);
}

static PyObject *
stepped_self(PyObject *self)
{
    return Py_NewRef(self);
}

static PyMethodDef stepped_methods[] = {
    {"send", (PyCFunction)stepped_send, METH_O,
     "Resume the body with value, or hand the task the thaw future while it is frozen."},
    {"throw", (PyCFunction)(void (*)(void))stepped_throw, METH_FASTCALL,
     "Throw an exception into the body at once, frozen or not (cancellation must arrive)."},
    {"close", (PyCFunction)stepped_close, METH_NOARGS,
     "Close the body (the task's coroutine is closed while it waits here)."},
    {NULL, NULL, 0, NULL},
};

static PyAsyncMethods stepped_async = {
    .am_await = (unaryfunc)stepped_self,
    .am_send = (sendfunc)stepped_am_send,
};

static PyTypeObject Stepped_Type = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "pyrobots_aio.actions._stepped.Stepped",
    .tp_doc = PyDoc_STR("The body coro, awaited through this: each resumption held while "
                        "handle is frozen (the pause trampoline, in C)."),
    .tp_basicsize = sizeof(Stepped),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_new = stepped_new,
    .tp_vectorcall = stepped_vectorcall,
    .tp_dealloc = (destructor)stepped_dealloc,
    .tp_traverse = (traverseproc)stepped_traverse,
    .tp_clear = (inquiry)stepped_clear,
    .tp_as_async = &stepped_async,
    .tp_iter = stepped_self,
    .tp_iternext = (iternextfunc)stepped_iternext,
    .tp_methods = stepped_methods,
};

/*
 * seal_weakrefs(cls): instances of cls refuse weak references from now on.
 *
 * For the mypyc-compiled generic classes (ActionHandle, Action, BoundAction):
 * mypyc gives them a weak-reference slot, but their tp_traverse and tp_clear
 * treat its list as an owned reference and their dealloc never clears it, so a
 * weak reference to one corrupts memory when the object goes. Sealed, a weak
 * reference fails with TypeError, as it does in the pure-Python build. Call it
 * at import, before any instance exists.
 */
static PyObject *
seal_weakrefs(PyObject *Py_UNUSED(module), PyObject *cls)
{
    if (!PyType_Check(cls)) {
        PyErr_Format(PyExc_TypeError, "seal_weakrefs() takes a class, not %R", cls);
        return NULL;
    }
    ((PyTypeObject *)cls)->tp_weaklistoffset = 0;
    PyType_Modified((PyTypeObject *)cls);
    Py_RETURN_NONE;
}

static PyMethodDef module_methods[] = {
    {"seal_weakrefs", (PyCFunction)seal_weakrefs, METH_O,
     "Make instances of cls refuse weak references (a compiled class's are unsafe)."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef stepped_module = {
    PyModuleDef_HEAD_INIT,
    .m_name = "pyrobots_aio.actions._stepped",
    .m_doc = PyDoc_STR("The pause trampoline, in C (see pyrobots_aio.actions._pause)."),
    .m_size = -1,
    .m_methods = module_methods,
};

PyMODINIT_FUNC
PyInit__stepped(void)
{
    str_paused = PyUnicode_InternFromString("paused");
    str_throw = PyUnicode_InternFromString("throw");
    str_close = PyUnicode_InternFromString("close");
    if (str_paused == NULL || str_throw == NULL || str_close == NULL) {
        return NULL;
    }
    if (PyType_Ready(&Stepped_Type) < 0) {
        return NULL;
    }
    PyObject *module = PyModule_Create(&stepped_module);
    if (module == NULL) {
        return NULL;
    }
    if (PyModule_AddObjectRef(module, "Stepped", (PyObject *)&Stepped_Type) < 0) {
        Py_DECREF(module);
        return NULL;
    }
    return module;
}
