/// Formats a printf-style pattern such as `cam%d/%05d.png` with integer
/// arguments, as the reference does with Python's `%` operator. Supports
/// `%d`, `%Nd`, `%0Nd` and `%%`; returns `None` for any other conversion or
/// a wrong number of arguments.
pub fn format_printf(pattern: &str, args: &[i64]) -> Option<String> {
    let mut out = String::with_capacity(pattern.len() + 8);
    let mut args = args.iter();
    let mut chars = pattern.chars().peekable();
    while let Some(ch) = chars.next() {
        if ch != '%' {
            out.push(ch);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            out.push('%');
            continue;
        }
        let zero = chars.peek() == Some(&'0');
        if zero {
            chars.next();
        }
        let mut width = 0usize;
        while let Some(d) = chars.peek().and_then(|c| c.to_digit(10)) {
            width = width * 10 + d as usize;
            chars.next();
        }
        if chars.next() != Some('d') {
            return None;
        }
        let v = args.next()?;
        if zero {
            out.push_str(&format!("{v:0width$}"));
        } else {
            out.push_str(&format!("{v:width$}"));
        }
    }
    if args.next().is_some() {
        return None;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::format_printf;

    #[test]
    fn formats_like_python() {
        assert_eq!(
            format_printf("cam%d/%05d.png", &[1, 42]).unwrap(),
            "cam1/00042.png"
        );
        assert_eq!(
            format_printf("cam%d/%04d.png", &[3, 1]).unwrap(),
            "cam3/0001.png"
        );
        assert_eq!(format_printf("%3d|%%", &[7]).unwrap(), "  7|%");
        assert!(format_printf("cam%d/%s.png", &[1, 2]).is_none());
        assert!(format_printf("cam%d.png", &[1, 2]).is_none());
        assert!(format_printf("cam%d/%d.png", &[1]).is_none());
    }
}
