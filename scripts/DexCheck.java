import java.io.File;
import java.util.EnumSet;
import java.util.Set;

import org.jf.dexlib2.DexFileFactory;
import org.jf.dexlib2.Opcode;
import org.jf.dexlib2.Opcodes;
import org.jf.dexlib2.iface.ClassDef;
import org.jf.dexlib2.iface.DexFile;
import org.jf.dexlib2.iface.Method;
import org.jf.dexlib2.iface.MethodImplementation;
import org.jf.dexlib2.iface.instruction.Instruction;
import org.jf.dexlib2.iface.instruction.ReferenceInstruction;

/**
 * scripts/android_dex_check.sh's reader: lists every instruction of a dex that needs the Java 7+ invokedynamic
 * machinery (none of which dx rewrites) and exits 1 when there is one. Run with dexlib2 on the class path:
 * java -cp dexlib2.jar:guava.jar scripts/DexCheck.java classes.dex
 */
public class DexCheck {
    private static final Set<Opcode> DYNAMIC = EnumSet.of(Opcode.INVOKE_CUSTOM, Opcode.INVOKE_CUSTOM_RANGE,
            Opcode.INVOKE_POLYMORPHIC, Opcode.INVOKE_POLYMORPHIC_RANGE, Opcode.CONST_METHOD_HANDLE,
            Opcode.CONST_METHOD_TYPE);

    public static void main(String[] args) throws Exception {
        DexFile dex = DexFileFactory.loadDexFile(new File(args[0]), Opcodes.forApi(28));
        int classes = 0;
        int found = 0;
        for (ClassDef c : dex.getClasses()) {
            classes++;
            for (Method m : c.getMethods()) {
                MethodImplementation code = m.getImplementation();
                if (code == null) {
                    continue;
                }
                for (Instruction i : code.getInstructions()) {
                    if (DYNAMIC.contains(i.getOpcode())) {
                        found++;
                        System.err.println("dex check: " + javaName(c.getType()) + "." + m.getName() + "("
                                + String.join("", m.getParameterTypes()) + ")" + m.getReturnType() + " uses "
                                + i.getOpcode().name + " " + ((ReferenceInstruction) i).getReference());
                    }
                }
            }
        }
        if (found > 0) {
            System.err.println("dex check FAILED: " + found + " invokedynamic instruction(s) in " + args[0]
                    + "; dx does not desugar and Android has no usable LambdaMetafactory: use an anonymous or"
                    + " named class instead (docs/android.md, \"Dex and API level checks\")");
            System.exit(1);
        }
        System.out.println("dex check: no invoke-custom, invoke-polymorphic or method-handle constant in "
                + classes + " classes of " + args[0]);
    }

    private static String javaName(String type) {
        return type.substring(1, type.length() - 1).replace('/', '.');
    }
}
