"""The one place where a control's widget and the session's state meet.

Every control of the page is a plain Panel widget bound here to one parameter of the
session's state (:func:`control`, :func:`bind`); nothing else links widgets to parameters
(no ``Widget.from_param``, no composite widget with a label of its own).

Why: a widget's value lives in two places, the browser's model and the server's copy, and
both sides write it. Pressing an arrow key on a slider seven times in half a second sends
seven values; the server handles them one by one on its worker threads (each one runs the
store's pass) and writes back what it derives from each. A value the server writes for an
older key press reaches the browser after the browser has moved on, and the server's final
write is dropped because its copy already holds the browser's final value: the page kept
showing "N: 70" with every plot at N = 100 (Panel's ``DiscreteSlider`` writes its label
from the browser and from the server; its shared "syncing" flag also dropped a change that
arrived on a second thread while the first one's pass ran). No ordering of writes can
avoid this crossing of messages; what settles it is a last word once the page is quiet.

So a :class:`Binder` (one per page) does three things:

* widget -> state: a change of the widget sets the parameter (a value the parameter
  refuses, or a text that is not a number, is answered by the binding's ``refused``
  callback and the widget goes back to the value in force);
* state -> widget: a change of the parameter (from a link, another control, a pin, the
  widget itself) sets the widget, echo-free per thread (a flag of the thread that writes,
  never one shared between threads);
* settle: once no bound widget or parameter has changed for :data:`QUIET_MS`, every
  binding touched since the last settle is set to the value in force and that value is
  sent to the browser again, even when the server believes the browser holds it (the
  message that crossed is then overwritten). The settle runs on the page's draw queue, in
  order with the views' draws.

Without a server (tests, reports) the bindings act at once and nothing needs settling.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
import weakref
from collections.abc import Callable, Iterator
from functools import partial
from typing import Any

import panel as pn
import param
from bokeh.document import without_document_lock

from ..runtime.draw import on_document, served_document
from ..runtime.panel_private import browser_change_pending, resend_value, respond_at_once

__all__ = ["QUIET_MS", "Binder", "Binding", "Refused", "bind", "control"]

log = logging.getLogger(__name__)

#: Milliseconds without a change of a bound widget or parameter after which the page is
#: quiet and its bindings are settled (longer than a fast key repeat, shorter than a
#: person's look at the result).
QUIET_MS = 350


class Refused(ValueError):
    """A widget value that does not become a value of its parameter (the message says why
    and is shown to the user)."""


def _same(a: Any, b: Any) -> bool:
    try:
        return bool(a == b)
    except Exception:  # arrays and the like: never equal here
        return a is b


class Binding:
    """One widget bound to ``obj.name``: ``to_widget(value)`` is what the widget shows for a
    parameter value, ``to_state(shown)`` the parameter value of what it shows (it raises
    :class:`Refused` for what it cannot read); ``refused(message)`` is told of a refusal
    (``""``: the value was taken)."""

    def __init__(
        self,
        widget: pn.widgets.Widget,
        obj: param.Parameterized,
        name: str,
        to_widget: Callable[[Any], Any] | None = None,
        to_state: Callable[[Any], Any] | None = None,
        refused: Callable[[str], None] | None = None,
        in_draw: bool = False,
    ) -> None:
        self.widget = widget
        self.obj = obj
        self.name = name
        self.to_widget = to_widget or (lambda v: v)
        self.to_state = to_state or (lambda v: v)
        self.refused = refused
        #: The parameter is set in a draw of the page (:func:`app.runtime.draw.on_document`):
        #: everything its watchers change on the page leaves in one message (a change of the
        #: whole page's layout, such as the view switch, is then laid out once).
        self.in_draw = in_draw
        #: User changes of the widget being handled now (on Panel's worker threads).
        self.busy = 0

    def in_flight(self) -> bool:
        """Whether a change of the widget from the browser is waiting or being handled: the
        widget may then show more than the state yet knows, and is not written over."""
        return self.busy > 0 or browser_change_pending(self.widget)

    def shown(self) -> Any:
        """What the widget must show: the value in force."""
        return self.to_widget(getattr(self.obj, self.name))


class Binder:
    """The bindings of one page (one served document; ``None``: no server)."""

    _binders: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
    _binders_lock = threading.Lock()

    def __init__(self, doc: Any = None) -> None:
        self._doc = weakref.ref(doc) if doc is not None else None
        self.bindings: list[Binding] = []
        self._dirty: dict[int, Binding] = {}
        self._lock = threading.Lock()
        self._last = 0.0
        self._waiting = False
        self._local = threading.local()  # the binding this thread is writing to its widget
        self.settles = 0  # (tests: how many settles ran)

    @classmethod
    def of(cls, doc: Any) -> Binder:
        """The binder of document ``doc`` (made on first use; ``None``: one without page)."""
        if doc is None:
            return cls(None)
        with cls._binders_lock:
            b = cls._binders.get(doc)
            if b is None:
                b = cls._binders[doc] = cls(doc)
            return b

    @property
    def doc(self) -> Any:
        return self._doc() if self._doc is not None else None

    # -- binding ---------------------------------------------------------------------------
    def bind(self, widget: pn.widgets.Widget, obj: param.Parameterized, name: str, **kw) -> Binding:
        """Bind ``widget`` to ``obj.name`` (keywords: those of :class:`Binding`); the widget
        shows the value in force at once."""
        b = Binding(widget, obj, name, **kw)
        self.bindings.append(b)
        with self._writing(b):
            widget.value = b.shown()
        widget.param.watch(lambda e, b=b: self._from_widget(b, e), "value")
        obj.param.watch(lambda e, b=b: self._from_state(b, e), name)
        respond_at_once(widget)
        return b

    def _writing_now(self) -> list:
        stack = getattr(self._local, "stack", None)
        if stack is None:
            stack = self._local.stack = []
        return stack

    @contextlib.contextmanager
    def _writing(self, b: Binding) -> Iterator[None]:
        """While this thread writes the value in force to ``b``'s widget (its own change
        of the widget is no user's change)."""
        stack = self._writing_now()
        stack.append(b)
        try:
            yield
        finally:
            stack.pop()

    def _from_widget(self, b: Binding, event: param.parameterized.Event) -> None:
        if any(w is b for w in self._writing_now()):
            return
        with self._lock:
            b.busy += 1
        try:
            self._take(b, event)
        finally:
            with self._lock:
                b.busy -= 1
        self._touch(b)

    def _take(self, b: Binding, event: param.parameterized.Event) -> None:
        try:
            value = b.to_state(event.new)
            if b.in_draw and self.doc is not None:
                on_document(self.doc, partial(b.obj.param.update, **{b.name: value}))
            elif not _same(value, getattr(b.obj, b.name)):
                b.obj.param.update(**{b.name: value})
        except (Refused, ValueError, TypeError) as exc:
            message = str(exc)
            if b.refused is not None:
                b.refused(message)
            else:
                log.info("a control's value was refused: %s", message)
        else:
            if b.refused is not None:
                b.refused("")
        if self.doc is None:
            self._show(b)  # no browser: the widget shows the value in force at once
        # served: the settle does, once the browser's change has been handled (a change of
        # the same property while Panel handles it is not sent back)

    def _from_state(self, b: Binding, event: param.parameterized.Event) -> None:
        # a widget the user is changing is not written over: it shows the user's newest
        # value, which the state is about to take (the settle writes it if not)
        if self.doc is None or not b.in_flight():
            self._show(b)
        self._touch(b)

    def _show(self, b: Binding) -> None:
        shown = b.shown()
        if not _same(b.widget.value, shown):
            with self._writing(b):
                b.widget.value = shown

    # -- settling --------------------------------------------------------------------------
    def _touch(self, b: Binding) -> None:
        doc = self.doc
        if doc is None:
            return
        with self._lock:
            self._dirty[id(b)] = b
            self._last = time.monotonic()
            if self._waiting:
                return
            self._waiting = True
        try:
            doc.add_next_tick_callback(self._wait_quiet)  # thread-safe in Bokeh
        except Exception:  # the session is gone
            with self._lock:
                self._waiting = False

    def _stirring(self) -> bool:
        """Whether a change is waiting, being handled or younger than :data:`QUIET_MS`
        (called with the binder's lock held)."""
        return any(b.in_flight() for b in self.bindings) or (
            self._last + QUIET_MS / 1000 > time.monotonic()
        )

    def _quiet_in(self) -> float:
        """Seconds until the page is quiet (0: quiet now): no change of a bound widget or
        parameter for :data:`QUIET_MS`, none waiting or being handled."""
        with self._lock:
            left = self._last + QUIET_MS / 1000 - time.monotonic()
            busy = any(b.in_flight() for b in self.bindings)
        if busy:
            return max(left, QUIET_MS / 1000)
        return max(left, 0.0)

    @without_document_lock
    async def _wait_quiet(self) -> None:
        while (left := self._quiet_in()) > 0:
            await asyncio.sleep(left)
        doc = self.doc
        if doc is not None and doc.session_context is not None:
            on_document(doc, self.settle)

    def settle(self) -> None:
        """Every binding touched since the last settle shows the value in force, and the
        browser is sent it again (run where the page's models may change); if a change
        came in meanwhile, the settle waits for the page to be quiet again."""
        doc = self.doc
        with self._lock:
            if doc is not None and self._stirring():
                self._waiting = True
                again = True
            else:
                self._waiting = False
                again = False
                dirty = list(self._dirty.values())
                self._dirty.clear()
        if again:
            doc.add_next_tick_callback(self._wait_quiet)
            return
        for b in dirty:
            try:
                self._show(b)
                if doc is not None:
                    resend_value(b.widget, doc)
            except Exception:
                log.exception("settling a control failed")
        self.settles += 1

    def mismatches(self) -> list[tuple[str, Any, Any]]:
        """``(parameter, widget value, value in force)`` of every binding whose widget does
        not show the value in force (tests)."""
        out = []
        for b in self.bindings:
            shown = b.shown()
            if not _same(b.widget.value, shown):
                out.append((f"{type(b.obj).__name__}.{b.name}", b.widget.value, shown))
        return out


def bind(widget: pn.widgets.Widget, obj: param.Parameterized, name: str, **kw) -> Binding:
    """Bind ``widget`` to ``obj.name`` on the current page (:class:`Binder`)."""
    return Binder.of(served_document()).bind(widget, obj, name, **kw)


def _options(p: param.Parameter) -> list:
    return list(p.objects) if getattr(p, "objects", None) is not None else []


def control(
    cls: type[pn.widgets.Widget],
    parameter: param.Parameter,
    *,
    to_widget: Callable[[Any], Any] | None = None,
    to_state: Callable[[Any], Any] | None = None,
    refused: Callable[[str], None] | None = None,
    in_draw: bool = False,
    **params: Any,
) -> pn.widgets.Widget:
    """A widget of class ``cls`` for ``parameter`` (of a ``Parameterized`` instance), bound
    to it (:func:`bind`): the replacement of ``cls.from_param``. ``name`` is its label;
    options and a slider's bounds and step come from the parameter unless given;
    ``in_draw``: see :class:`Binding`."""
    obj, name = parameter.owner, parameter.name
    if "name" not in params:
        params["name"] = parameter.label
    if "options" in cls.param and "options" not in params:
        params["options"] = _options(parameter)
    if "start" in cls.param and "start" not in params and parameter.bounds is not None:
        lo, hi = parameter.get_soft_bounds()
        params["start"] = lo
        params.setdefault("end", hi)
    if "step" in cls.param and "step" not in params and getattr(parameter, "step", None):
        params["step"] = parameter.step
    value = getattr(obj, name)
    params["value"] = to_widget(value) if to_widget is not None else value
    if "description" in cls.param and "description" not in params and parameter.doc:
        params["description"] = " ".join(parameter.doc.split())
    widget = cls(**params)
    bind(
        widget, obj, name, to_widget=to_widget, to_state=to_state, refused=refused, in_draw=in_draw
    )
    return widget
