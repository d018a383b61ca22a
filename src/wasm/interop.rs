//! Every JS <-> Rust conversion of the facade: reading what the user hands
//! to the wasm API (through catching imports only), the shared config
//! checker, "undefined/null means default", and results as JS values.
//!
//! Why: a JS exception thrown inside an import that is not declared `catch`
//! (a getter or Proxy trap reached by `Object.keys`, by serde-wasm-bindgen's
//! property reads, by a typed array's `set` on a detached buffer) unwinds
//! straight past the wasm frames. The shadow-stack pointer is then never
//! restored and the `&mut self` borrow wasm-bindgen holds for a method is
//! never released: after ~60 such calls every call traps, and the object
//! answers "recursive use of an object detected" for ever. Here every read
//! of a user value is a `Reflect` call (declared `catch` in js-sys) or an
//! intrinsic typed-array accessor bound `final` (looked up on
//! `%TypedArray%.prototype` at instantiation, so no own property or Proxy of
//! the user's can stand in for it) and `catch`. A throw becomes an `Err`
//! naming what was being read, and the caller returns it as a JS `Error`.
//!
//! Sizes are checked before anything is allocated, and allocations are
//! fallible (`try_reserve`), so a huge length is an error naming the limit,
//! not a trap.

use js_sys::{Array, Float64Array, Object, Reflect, Uint8Array};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::{Map, Number, Value};
use wasm_bindgen::prelude::*;
use wasm_bindgen::JsCast;

use crate::config::Data;
use crate::logs::decimal::Shortest;

#[wasm_bindgen]
extern "C" {
    /// A value checked to be some typed array (the accessors below throw,
    /// caught, on anything else).
    #[wasm_bindgen(js_name = Float64Array)]
    type Typed;
    /// `%TypedArray%.prototype.length`: elements, 0 once detached.
    #[wasm_bindgen(catch, method, getter, final, js_class = "Float64Array", js_name = length)]
    fn checked_length(this: &Typed) -> Result<f64, JsValue>;
    #[wasm_bindgen(catch, method, getter, final, js_class = "Float64Array", js_name = buffer)]
    fn checked_buffer(this: &Typed) -> Result<JsValue, JsValue>;
    #[wasm_bindgen(catch, method, getter, final, js_class = "Float64Array", js_name = byteOffset)]
    fn checked_byte_offset(this: &Typed) -> Result<f64, JsValue>;
    /// `%TypedArray%.prototype.set(src, offset)`: throws (caught) on a
    /// detached source or target, or a source that does not fit.
    #[wasm_bindgen(catch, method, final, js_class = "Float64Array", js_name = set)]
    fn checked_set(this: &Typed, src: &JsValue, offset: f64) -> Result<(), JsValue>;
}

/// Largest nesting of a plain-data value (config, options, tight rows).
const MAX_DEPTH: usize = 32;
/// Largest number of values (numbers, strings, array slots) in one
/// plain-data value: a model with q = 100 000 has 4·10⁵ numbers.
pub const MAX_PLAIN_VALUES: usize = 4_000_000;

/// A thrown JS value as text (its `message` if it has one).
pub fn describe(e: &JsValue) -> String {
    if let Some(s) = e.as_string() {
        return s;
    }
    if e.is_object() {
        if let Ok(m) = Reflect::get(e, &JsValue::from_str("message")) {
            if let Some(s) = m.as_string() {
                return s;
            }
        }
    }
    "a non-Error value was thrown".to_string()
}

/// `obj[key]`; a throwing getter or Proxy trap is an error naming `what`.
pub fn get(obj: &JsValue, key: &JsValue, what: &str) -> Result<JsValue, String> {
    Reflect::get(obj, key).map_err(|e| format!("{what}: reading it threw: {}", describe(&e)))
}

/// Own enumerable string keys (as `Object.keys`, but through catching calls).
pub fn own_keys(obj: &JsValue, what: &str) -> Result<Vec<String>, String> {
    let o: &Object = obj.unchecked_ref();
    let keys = Reflect::own_keys(o).map_err(|e| format!("{what}: listing its fields threw: {}", describe(&e)))?;
    let mut out = Vec::new();
    for k in keys.iter() {
        // Symbol keys are not data fields.
        let Some(name) = k.as_string() else { continue };
        let desc = Reflect::get_own_property_descriptor(o, &k).map_err(|e| format!("{what}.{name}: reading it threw: {}", describe(&e)))?;
        // The engine builds the descriptor object itself: plain data.
        if desc.is_object() && get(&desc, &JsValue::from_str("enumerable"), what)?.as_bool() == Some(true) {
            out.push(name);
        }
    }
    Ok(out)
}

/// A JS number as plain data: integers (other than −0) as integers, as
/// serde_json reads them from JSON text, so that integer fields deserialize
/// and messages name them so; non-finite numbers are an error (JSON has none).
fn number(x: f64, path: &str) -> Result<Data, String> {
    if !x.is_finite() {
        return Err(format!("{path}: must be a finite number, got {}", Shortest(x)));
    }
    let integral = x.fract() == 0.0 && x.abs() < 9.0e15 && !(x == 0.0 && x.is_sign_negative());
    Ok(match (integral, x >= 0.0) {
        (true, true) => Data::U(x as u64),
        (true, false) => Data::I(x as i64),
        (false, _) => Data::F(x),
    })
}

/// Copy a user value into plain data (what `JSON.parse(JSON.stringify(v))`
/// would give, but with every read caught and errors naming the path).
/// `None` for `undefined` (an absent field). [`Data`], not serde_json's
/// `Value`: the core module reads its config from it and so carries no
/// `Value` or map; the lab's options go on to serde through [`json_of`].
pub fn plain(v: &JsValue, path: &str) -> Result<Option<Data>, String> {
    let mut budget = MAX_PLAIN_VALUES;
    plain_at(v, path, 0, &mut budget)
}

fn plain_at(v: &JsValue, path: &str, depth: usize, budget: &mut usize) -> Result<Option<Data>, String> {
    if *budget == 0 {
        return Err(format!("{path}: too large (more than {MAX_PLAIN_VALUES} values)"));
    }
    *budget -= 1;
    if v.is_undefined() {
        return Ok(None);
    }
    if v.is_null() {
        return Ok(Some(Data::Null));
    }
    if let Some(b) = v.as_bool() {
        return Ok(Some(Data::Bool(b)));
    }
    if let Some(x) = v.as_f64() {
        return number(x, path).map(Some);
    }
    if let Some(s) = v.as_string() {
        return Ok(Some(Data::Str(s)));
    }
    if !v.is_object() || v.is_function() {
        let kind = v.js_typeof().as_string().unwrap_or_default();
        return Err(format!("{path}: a {kind} is not plain data"));
    }
    if depth >= MAX_DEPTH {
        return Err(format!("{path}: nested more than {MAX_DEPTH} levels deep"));
    }
    // `instanceof` checks are wrapped in try/catch by wasm-bindgen's glue.
    if v.is_instance_of::<Array>() {
        let n = array_len(v, path, *budget)?;
        let mut out = Vec::new();
        out.try_reserve_exact(n).map_err(|_| format!("{path}: cannot allocate {n} elements"))?;
        for i in 0..n {
            let p = format!("{path}[{i}]");
            let x = get(v, &JsValue::from(i as f64), &p)?;
            out.push(plain_at(&x, &p, depth + 1, budget)?.unwrap_or(Data::Null));
        }
        return Ok(Some(Data::Arr(out)));
    }
    let mut out = Vec::new();
    for k in own_keys(v, path)? {
        let p = format!("{path}.{k}");
        let x = get(v, &JsValue::from_str(&k), &p)?;
        if let Some(x) = plain_at(&x, &p, depth + 1, budget)? {
            out.push((k, x));
        }
    }
    Ok(Some(Data::Obj(out)))
}

/// Plain data as serde_json's, for serde to read (the lab's options).
fn json_of(d: Data) -> Value {
    match d {
        Data::Null => Value::Null,
        Data::Bool(b) => Value::Bool(b),
        Data::U(u) => Value::Number(u.into()),
        Data::I(i) => Value::Number(i.into()),
        // Finite (checked by `number`), so always a JSON number.
        Data::F(x) => Number::from_f64(x).map_or(Value::Null, Value::Number),
        Data::Str(s) => Value::String(s),
        Data::Arr(a) => Value::Array(a.into_iter().map(json_of).collect()),
        Data::Obj(o) => {
            // Inserted one by one: `collect` would bring in the map's bulk
            // build (a sort) too.
            let mut m = Map::new();
            for (k, v) in o {
                m.insert(k, json_of(v));
            }
            Value::Object(m)
        }
    }
}

/// `v.length` of an array-like, checked to be an integer no larger than `max`.
fn array_len(v: &JsValue, what: &str, max: usize) -> Result<usize, String> {
    let len = get(v, &JsValue::from_str("length"), what)?;
    match len.as_f64() {
        Some(n) if n >= 0.0 && n.fract() == 0.0 && n <= max as f64 => Ok(n as usize),
        Some(n) if n >= 0.0 && n.fract() == 0.0 => Err(format!("{what}: length {} exceeds the limit of {max}", Shortest(n))),
        _ => Err(format!("{what}: length must be a non-negative integer")),
    }
}

/// Elements of a typed array of type `T` (element kind named `kind`),
/// checked to be a real one with at most `max` elements. A detached one reads
/// as 0 elements; copying from it throws, caught.
fn typed_len<T: JsCast>(v: &JsValue, max: usize, what: &str, kind: &str) -> Result<usize, String> {
    if !v.is_instance_of::<T>() {
        return Err(format!("{what}: must be a {kind}"));
    }
    let len = v.unchecked_ref::<Typed>().checked_length().map_err(|_| format!("{what}: must be a {kind}"))?;
    if len > max as f64 {
        return Err(format!("{what}: {} elements exceed the limit of {max} per call", Shortest(len)));
    }
    Ok(len as usize)
}

fn unreadable(what: &str, e: &JsValue) -> String {
    format!("{what}: unreadable (detached buffer?): {}", describe(e))
}

/// Element types whose all-zero bytes are a value (0, 0.0).
trait Zeroable: Copy {}
impl Zeroable for u8 {}
impl Zeroable for f64 {}

/// Copy the whole typed array `src` (of `n` elements, as checked) into `dst`.
fn copy_all<E: Zeroable>(src: &JsValue, n: usize, dst: &mut Vec<E>, view: unsafe fn(*mut E, usize) -> JsValue, what: &str) -> Result<(), String> {
    dst.clear();
    dst.try_reserve_exact(n).map_err(|_| format!("{what}: cannot allocate {n} elements"))?;
    // Zeroed in one `memory.fill` (this crate is built for size in the core
    // module, where `resize` would be a loop over the elements, megabytes
    // of a log).
    // SAFETY: `n` elements were reserved, and all-zero bytes are a value of
    // `E` (`Zeroable`).
    unsafe {
        core::ptr::write_bytes(dst.as_mut_ptr(), 0, n);
        dst.set_len(n);
    }
    // SAFETY: the view covers `dst`'s n initialised elements and is used at
    // once, before anything can allocate in wasm memory.
    let v = unsafe { view(dst.as_mut_ptr(), n) };
    v.unchecked_ref::<Typed>().checked_set(src, 0.0).map_err(|e| unreadable(what, &e))
}

unsafe fn f64_view(p: *mut f64, n: usize) -> JsValue {
    Float64Array::view_mut_raw(p, n).into()
}

unsafe fn u8_view(p: *mut u8, n: usize) -> JsValue {
    Uint8Array::view_mut_raw(p, n).into()
}

/// Write `src` into the user's typed array `out` from element `at` (checked
/// by the caller to fit).
pub fn write_f64(out: &JsValue, at: usize, src: &[f64], what: &str) -> Result<(), String> {
    // SAFETY: a read-only view on `src`, used at once (as in `copy_all`).
    let v = unsafe { Float64Array::view(src) };
    out.unchecked_ref::<Typed>().checked_set(&v, at as f64).map_err(|e| unreadable(what, &e))
}

/// Write `src` into our own Uint8Array `out` from element `at`.
pub fn write_u8(out: &JsValue, at: usize, src: &[u8], what: &str) -> Result<(), String> {
    // SAFETY: as in `write_f64`.
    let v = unsafe { Uint8Array::view(src) };
    out.unchecked_ref::<Typed>().checked_set(&v, at as f64).map_err(|e| unreadable(what, &e))
}

/// A new zero-filled typed array of `n` elements, made by `ctor` through a
/// catching call: a failed allocation is an error, not an uncaught throw.
pub fn new_typed(ctor: &JsValue, n: usize, what: &str) -> Result<JsValue, String> {
    Reflect::construct(ctor.unchecked_ref::<js_sys::Function>(), &Array::of1(&JsValue::from(n as f64))).map_err(|e| format!("{what}: cannot allocate {n} elements: {}", describe(&e)))
}

/// The Float64Array constructor.
pub fn f64_ctor() -> JsValue {
    Float64Array::new_with_length(0).constructor().into()
}

/// The Uint8Array constructor.
pub fn u8_ctor() -> JsValue {
    Uint8Array::new_with_length(0).constructor().into()
}

/// A Float64Array checked to be real and attached, to be copied from in
/// slices (a batch too large to copy whole): its `buffer` and `byteOffset`,
/// read once through the intrinsic accessors.
pub struct F64Source {
    buffer: JsValue,
    byte_offset: f64,
    len: usize,
}

impl F64Source {
    /// Check `v` (at most `max` elements; `what` names it in errors) and
    /// read its buffer and offset once.
    pub fn new(v: &JsValue, max: usize, what: &str) -> Result<Self, String> {
        let len = typed_len::<Float64Array>(v, max, what, "Float64Array")?;
        let t: &Typed = v.unchecked_ref();
        let not = |_| format!("{what}: must be a Float64Array");
        let src = F64Source { buffer: t.checked_buffer().map_err(not)?, byte_offset: t.checked_byte_offset().map_err(not)?, len };
        // A detached buffer reads as length 0; a view on it throws, caught.
        src.view(0, 0, what)?;
        Ok(src)
    }

    /// Elements in the array.
    pub fn len(&self) -> usize {
        self.len
    }

    /// A fresh view of elements `a..b` on the same buffer (no species
    /// lookup, so no user code runs).
    fn view(&self, a: usize, b: usize, what: &str) -> Result<JsValue, String> {
        let args = Array::of3(&self.buffer, &JsValue::from(self.byte_offset + (a * 8) as f64), &JsValue::from((b - a) as f64));
        Reflect::construct(f64_ctor().unchecked_ref::<js_sys::Function>(), &args).map_err(|e| unreadable(what, &e))
    }

    /// Elements `a..b` (`a ≤ b ≤ len`) into `dst` (replacing its contents).
    pub fn read(&self, a: usize, b: usize, dst: &mut Vec<f64>, what: &str) -> Result<(), String> {
        let src = self.view(a, b, what)?;
        copy_all(&src, b - a, dst, f64_view, what)
    }
}

/// Numbers from a Float64Array or a plain array of numbers (`null` and
/// `undefined` read as NaN, "absent"), at most `max` of them, into `dst`.
pub fn f64s(v: &JsValue, max: usize, what: &str, dst: &mut Vec<f64>) -> Result<(), String> {
    if v.is_instance_of::<Float64Array>() {
        let n = typed_len::<Float64Array>(v, max, what, "Float64Array")?;
        return copy_all(v, n, dst, f64_view, what);
    }
    if !v.is_instance_of::<Array>() {
        return Err(format!("{what}: must be a Float64Array or an array of numbers"));
    }
    let n = array_len(v, what, max)?;
    dst.clear();
    dst.try_reserve_exact(n).map_err(|_| format!("{what}: cannot allocate {n} values"))?;
    for i in 0..n {
        let x = get(v, &JsValue::from(i as f64), what)?;
        if x.is_undefined() || x.is_null() {
            dst.push(f64::NAN);
        } else {
            dst.push(x.as_f64().ok_or_else(|| format!("{what}[{i}]: must be a number"))?);
        }
    }
    Ok(())
}

/// Elements of a Float64Array `out` the caller may write (checked: a real,
/// attached Float64Array; a detached one has 0).
pub fn f64_out_len(out: &JsValue, what: &str) -> Result<usize, String> {
    typed_len::<Float64Array>(out, usize::MAX, what, "Float64Array")
}

/// Bytes from a Uint8Array (a Node Buffer is one) or a plain array of
/// integers 0..=255.
pub fn bytes(v: &JsValue, max: usize, what: &str) -> Result<Vec<u8>, String> {
    let mut out = Vec::new();
    if v.is_instance_of::<Uint8Array>() {
        let n = typed_len::<Uint8Array>(v, max, what, "Uint8Array")?;
        copy_all(v, n, &mut out, u8_view, what)?;
        return Ok(out);
    }
    if !v.is_instance_of::<Array>() {
        return Err(format!("{what}: must be a Uint8Array"));
    }
    let n = array_len(v, what, max)?;
    out.try_reserve_exact(n).map_err(|_| format!("{what}: cannot allocate {n} bytes"))?;
    for i in 0..n {
        match get(v, &JsValue::from(i as f64), what)?.as_f64() {
            Some(x) if x.fract() == 0.0 && (0.0..=255.0).contains(&x) => out.push(x as u8),
            _ => return Err(format!("{what}[{i}]: must be an integer in 0..=255")),
        }
    }
    Ok(out)
}

/// The elements of a plain array (at most `max`).
pub fn items(v: &JsValue, max: usize, what: &str) -> Result<Vec<JsValue>, String> {
    if !v.is_instance_of::<Array>() {
        return Err(format!("{what}: must be an array"));
    }
    let n = array_len(v, what, max)?;
    (0..n).map(|i| get(v, &JsValue::from(i as f64), &format!("{what}[{i}]"))).collect()
}

/// A string of at most `max` UTF-16 units (checked before it is copied).
pub fn string(v: &JsValue, max: usize, what: &str) -> Result<String, String> {
    let Some(s) = v.dyn_ref::<js_sys::JsString>() else {
        return Err(format!("{what}: must be a string"));
    };
    let n = s.length() as usize;
    if n > max {
        return Err(format!("{what}: {n} characters exceed the limit of {max}"));
    }
    v.as_string().ok_or_else(|| format!("{what}: must be a string"))
}

/// A number argument (no coercion: an object's `valueOf` never runs).
pub fn num(v: &JsValue, what: &str) -> Result<f64, String> {
    v.as_f64().ok_or_else(|| format!("{what}: must be a number"))
}

/// An optional boolean argument (`undefined` / `null`: false).
pub fn flag(v: &JsValue, what: &str) -> Result<bool, String> {
    match given(v) {
        None => Ok(false),
        Some(v) => v.as_bool().ok_or_else(|| format!("{what}: must be a boolean")),
    }
}

/// The one rule for optional arguments and options: `undefined` and `null`
/// mean "use the default" (`None`); anything else is the value to check.
pub fn given(v: &JsValue) -> Option<&JsValue> {
    if v.is_undefined() || v.is_null() {
        None
    } else {
        Some(v)
    }
}

/// A message as a JS `Error`.
pub fn err(msg: impl core::fmt::Display) -> JsError {
    JsError::new(&msg.to_string())
}

/// Largest byte input (a log, a snapshot, a CSV chunk) per call.
pub const MAX_BYTES: usize = 1 << 31;
/// Largest numeric array per call (`metrics`).
pub const MAX_VALUES: usize = 1 << 27;
/// Largest text argument (`TightDetector.pushCsv`), UTF-16 units.
pub const MAX_TEXT: usize = 1 << 26;
/// Largest name argument (scenario, log name).
pub const MAX_NAME: usize = 4096;

/// The checked detector config: the same checker as
/// `ConfigInput::from_json` (both go through `ConfigInput::from_data`).
/// Fields are read once each, by name, through catching calls: a throwing
/// getter or Proxy trap is a config error naming the field, and nothing is
/// left half-done.
pub fn config_from(v: &JsValue) -> Result<crate::config::Config, JsError> {
    use crate::config::ConfigInput;
    let Some(v) = given(v) else { return Ok(crate::config::Config::default()) };
    if !v.is_object() || v.is_function() {
        return Err(err("config: must be a plain object"));
    }
    for name in own_keys(v, "config").map_err(err)? {
        ConfigInput::check_field_name(&name).map_err(err)?;
    }
    let mut fields = Vec::new();
    for name in ConfigInput::FIELDS {
        let what = format!("config.{name}");
        let x = get(v, &JsValue::from_str(name), &what).map_err(err)?;
        if let Some(x) = plain(&x, &what).map_err(err)? {
            fields.push((name.to_string(), x));
        }
    }
    ConfigInput::from_data(Data::Obj(fields)).map_err(err)
}

/// A user object as `T`, copied to plain data first (see [`plain`]);
/// `undefined` / `null` give `T::default()`.
pub fn options<T: DeserializeOwned + Default>(v: &JsValue, what: &str) -> Result<T, JsError> {
    match given(v) {
        None => Ok(T::default()),
        Some(v) => plain_of(v, what),
    }
}

/// A user object as `T`, copied to plain data first (see [`plain`]).
pub fn plain_of<T: DeserializeOwned>(v: &JsValue, what: &str) -> Result<T, JsError> {
    let x = plain(v, what).map_err(err)?.map_or(Value::Null, json_of);
    serde_json::from_value(x).map_err(|e| err(format!("{what}: {e}")))
}

/// A result as a plain JS value (maps as objects, `None` as undefined).
pub fn to_js<T: Serialize + ?Sized>(x: &T) -> Result<JsValue, JsError> {
    let ser = serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true);
    x.serialize(&ser).map_err(err)
}

/// `o[k] = v` on a fresh plain object of ours (cannot fail).
pub fn set(o: &Object, k: &str, v: &JsValue) {
    let _ = Reflect::set(o, &JsValue::from_str(k), v);
}

/// A result as a plain JS object, built field by field: what [`to_js`]
/// gives for a struct (its fields in declaration order, `None` as a field
/// holding `undefined`, integers as numbers), without serde's code in the
/// core module. The core module's results are built with it; the lab's
/// still go through [`to_js`].
pub struct Obj(Object);

impl Obj {
    /// An empty plain object.
    pub fn new() -> Obj {
        Obj(Object::new())
    }
    /// `k`: any JS value.
    pub fn v(self, k: &str, v: &JsValue) -> Obj {
        set(&self.0, k, v);
        self
    }
    /// `k`: a number (an integer counter as serde-wasm-bindgen writes it, as
    /// an f64).
    pub fn n(self, k: &str, v: f64) -> Obj {
        self.v(k, &JsValue::from_f64(v))
    }
    /// `k`: a number, or `undefined` for `None` (the field is still there).
    pub fn opt(self, k: &str, v: Option<f64>) -> Obj {
        self.v(k, &v.map_or(JsValue::UNDEFINED, JsValue::from_f64))
    }
    /// `k`: a boolean.
    pub fn b(self, k: &str, v: bool) -> Obj {
        self.v(k, &JsValue::from_bool(v))
    }
    /// `k`: a string.
    pub fn s(self, k: &str, v: &str) -> Obj {
        self.v(k, &JsValue::from_str(v))
    }
    /// The object.
    pub fn done(self) -> JsValue {
        self.0.into()
    }
}

/// A JS array of the values `f` makes of `items`.
pub fn array_of<T>(items: &[T], f: impl Fn(&T) -> JsValue) -> JsValue {
    let a = Array::new();
    for x in items {
        a.push(&f(x));
    }
    a.into()
}

/// Strings as a JS array of strings.
pub fn strings(items: &[String]) -> JsValue {
    array_of(items, |s| JsValue::from_str(s))
}

/// `(key, value)` pairs as a JS array of two-element arrays.
pub fn string_pairs(items: &[(String, String)]) -> JsValue {
    array_of(items, |(k, v)| Array::of2(&JsValue::from_str(k), &JsValue::from_str(v)).into())
}

/// The detector's counters as JS sees them (camelCase, like the rest of the API).
pub fn stats_object(s: &crate::detector::Stats) -> JsValue {
    Obj::new()
        .n("rows", s.rows as f64)
        .n("gpsEpochs", s.gps_epochs as f64)
        .n("imuRows", s.imu_rows as f64)
        .n("baroRows", s.baro_rows as f64)
        .n("retrains", s.retrains as f64)
        .n("filterResets", s.filter_resets as f64)
        .n("dataGaps", s.data_gaps as f64)
        .n("filterErrors", s.filter_errors as f64)
        .done()
}
