//! Constant evaluation of tree expressions: what a param's default or range
//! is, and whether a constant set on a field lies in the field's range.

use crate::material::tree::{BinOp, Builtin, ExprId, ExprKind, Value};

/// The value of `id` when every leaf below it is a constant.
pub fn constant(exprs: &[crate::material::tree::Expr], id: ExprId) -> Option<Value> {
    let e = &exprs[id.0 as usize];
    let v = |id: ExprId| constant(exprs, id);
    Some(match &e.kind {
        ExprKind::Const(c) => *c,
        ExprKind::Param(_) => return None,
        ExprKind::Neg(a) => map(v(*a)?, |x| -x),
        ExprKind::Binary(op, a, b) => {
            let f: fn(f32, f32) -> f32 = match op {
                BinOp::Add => |x, y| x + y,
                BinOp::Sub => |x, y| x - y,
                BinOp::Mul => |x, y| x * y,
                BinOp::Div => |x, y| x / y,
            };
            zip(v(*a)?, v(*b)?, f)
        }
        ExprKind::Call(b, args) => {
            let a: Vec<Value> = args.iter().map(|&a| v(a)).collect::<Option<_>>()?;
            builtin(*b, &a)?
        }
    })
}

/// Every component of a value.
pub fn components(v: Value) -> Vec<f32> {
    match v {
        Value::Float(x) => vec![x],
        Value::Vec3(c) => c.to_vec(),
    }
}

fn map(v: Value, f: impl Fn(f32) -> f32) -> Value {
    match v {
        Value::Float(x) => Value::Float(f(x)),
        Value::Vec3(c) => Value::Vec3(c.map(f)),
    }
}

/// `f` per component, a float broadcast against a vector.
fn zip(a: Value, b: Value, f: impl Fn(f32, f32) -> f32) -> Value {
    match (a, b) {
        (Value::Float(x), Value::Float(y)) => Value::Float(f(x, y)),
        (a, b) => {
            let (a, b) = (spread(a), spread(b));
            Value::Vec3([0, 1, 2].map(|i| f(a[i], b[i])))
        }
    }
}

fn spread(v: Value) -> [f32; 3] {
    match v {
        Value::Float(x) => [x; 3],
        Value::Vec3(c) => c,
    }
}

fn builtin(b: Builtin, a: &[Value]) -> Option<Value> {
    let lum = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let srgb = |x: f32| if x <= 0.04045 { x / 12.92 } else { ((x + 0.055) / 1.055).powf(2.4) };
    Some(match (b, a) {
        (Builtin::Rgb, [Value::Float(r), Value::Float(g), Value::Float(bl)]) => Value::Vec3([*r, *g, *bl]),
        (Builtin::Grey, [Value::Float(x)]) => Value::Vec3([*x; 3]),
        (Builtin::Lerp, [x, y, t]) => zip(zip(*x, *t, |x, t| x * (1.0 - t)), zip(*y, *t, |y, t| y * t), |p, q| p + q),
        (Builtin::Clamp, [x, lo, hi]) => zip(zip(*x, *lo, f32::max), *hi, f32::min),
        (Builtin::Saturate, [x]) => map(*x, |x| x.clamp(0.0, 1.0)),
        (Builtin::Min, [x, y]) => zip(*x, *y, f32::min),
        (Builtin::Max, [x, y]) => zip(*x, *y, f32::max),
        (Builtin::Pow, [x, y]) => zip(*x, *y, f32::powf),
        (Builtin::Sqrt, [x]) => map(*x, f32::sqrt),
        (Builtin::Abs, [x]) => map(*x, f32::abs),
        (Builtin::Luminance, [c]) => Value::Float(lum(spread(*c))),
        (Builtin::Srgb, [c]) => map(*c, srgb),
        (Builtin::IorToF0, [x]) => map(*x, |n| ((n - 1.0) / (n + 1.0)).powi(2)),
        (Builtin::TransmittanceToMfp, [c, d]) => zip(*c, *d, |c, d| -d / c.ln()),
        _ => return None,
    })
}
