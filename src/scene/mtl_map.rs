//! An MTL texture statement (`map_Kd -clamp on -s 2 2 1 leaf.png`): its
//! options, then the file name, which may hold spaces (the Wavefront MTL
//! specification's option list). `tobj` hands over the whole rest of the
//! line as the name, so Blender's `map_Bump -bm 1.000000 normal.png` named
//! a file that is not there.

/// What a texture statement says.
#[derive(Debug, PartialEq)]
pub struct MtlMap<'a> {
    /// The image file, relative to the MTL file.
    pub file: &'a str,
    /// `-clamp on`: coordinates outside [0, 1] read the border texels
    /// (glTF's CLAMP_TO_EDGE) instead of repeating.
    pub clamp: bool,
    /// Options given that change what is read and that the loader does not
    /// apply (`-o`, `-s`, `-t` move and scale the coordinates, `-mm` remaps
    /// the values, `-imfchan` picks a channel).
    pub ignored: Vec<&'a str>,
}

/// The least and most arguments an option takes: `-o`, `-s` and `-t` one
/// to three numbers, the others a fixed count; `None` for a word that is
/// no option (the file name starts there).
fn arity(option: &str) -> Option<(usize, usize)> {
    Some(match option {
        "-blendu" | "-blendv" | "-cc" | "-clamp" | "-texres" | "-bm" | "-boost" | "-imfchan"
        | "-type" => (1, 1),
        "-mm" => (2, 2),
        "-o" | "-s" | "-t" => (1, 3),
        _ => return None,
    })
}

/// The first word of `s` and what follows it, both without leading blanks.
fn split_word(s: &str) -> (&str, &str) {
    let s = s.trim_start();
    let end = s.find(char::is_whitespace).unwrap_or(s.len());
    (&s[..end], s[end..].trim_start())
}

/// Parses the text after a `map_*` keyword; an error says what is wrong (an
/// option without its arguments, `-clamp` neither on nor off, no file).
pub fn parse(statement: &str) -> Result<MtlMap<'_>, String> {
    let mut map = MtlMap {
        file: "",
        clamp: false,
        ignored: vec![],
    };
    let mut rest = statement.trim();
    loop {
        let (option, mut tail) = split_word(rest);
        let Some((min, max)) = arity(option) else {
            break;
        };
        let mut args = vec![];
        while args.len() < max {
            let (arg, after) = split_word(tail);
            // Past the least count only numbers are arguments.
            if arg.is_empty() || (args.len() >= min && arg.parse::<f32>().is_err()) {
                break;
            }
            args.push(arg);
            tail = after;
        }
        if args.len() < min {
            return Err(format!("option {option} needs {min} argument(s)"));
        }
        match (option, args[0]) {
            ("-clamp", "on") => map.clamp = true,
            ("-clamp", "off") => map.clamp = false,
            ("-clamp", other) => return Err(format!("-clamp {other}: not on or off")),
            ("-o" | "-s" | "-t" | "-mm" | "-imfchan", _) => map.ignored.push(option),
            _ => {}
        }
        rest = tail;
    }
    if rest.is_empty() {
        return Err("no file name".into());
    }
    map.file = rest;
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Options of fixed and of variable count are skipped to the name,
    /// which keeps its spaces; `-clamp on` is read; options that move,
    /// scale or remap what is read are listed as not applied.
    #[test]
    fn options_come_off_the_file_name() {
        let plain = parse("leaf.png").unwrap();
        assert_eq!((plain.file, plain.clamp), ("leaf.png", false));
        let blender = parse("-bm 1.000000 normal map.png").unwrap();
        assert_eq!(blender.file, "normal map.png");
        assert!(blender.ignored.is_empty());
        let many = parse("-clamp on -s 2 2 -o 0.5 -blendu off -bm -0.5 textures/leaf.png").unwrap();
        assert_eq!(many.file, "textures/leaf.png");
        assert!(many.clamp);
        assert_eq!(many.ignored, ["-s", "-o"]);
        // Three numbers at most: the fourth word is the name.
        assert_eq!(parse("-s 1 2 3 4.png").unwrap().file, "4.png");
        // A name that starts with a dash but is no option.
        assert_eq!(parse("-leaf.png").unwrap().file, "-leaf.png");
    }

    #[test]
    fn malformed_statements_say_why() {
        assert!(
            parse("-clamp maybe leaf.png")
                .unwrap_err()
                .contains("-clamp maybe")
        );
        assert!(parse("-clamp on").unwrap_err().contains("no file name"));
        assert!(parse("-mm 0.5").unwrap_err().contains("-mm needs 2"));
        assert!(parse("   ").unwrap_err().contains("no file name"));
    }
}
